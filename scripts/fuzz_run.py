#!/usr/bin/env python3
"""Runs one libFuzzer target for scripts/fuzz.sh and records what it cost. The target runs
until libFuzzer stops it (its own -max_total_time, wall seconds, or a finding) or, with --cpu,
until it has used that many CPU seconds (user + system): then it gets SIGINT, which libFuzzer
answers with its final statistics. A campaign on a shared machine is sized in CPU seconds, a CI
pass in wall seconds. Writes {"wall_s", "cpu_s", "exit", "interrupted"} to --record.
Usage: fuzz_run.py --record FILE [--cpu SECONDS] -- FUZZER ARGS...
Exit status: the fuzzer's (0 after the SIGINT it was sent).
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import time

TICKS = os.sysconf("SC_CLK_TCK")


def cpu_seconds(pid):
    """utime + stime of a running process, from /proc (0 once it is gone)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / TICKS
    except (OSError, IndexError, ValueError):
        return 0.0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--record", required=True)
    ap.add_argument("--cpu", type=float, default=0)
    ap.add_argument("command", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    command = a.command[1:] if a.command[:1] == ["--"] else a.command
    start = time.monotonic()
    proc = subprocess.Popen(command)
    interrupted = False
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        if a.cpu and not interrupted and cpu_seconds(proc.pid) >= a.cpu:
            proc.send_signal(signal.SIGINT)
            interrupted = True
        time.sleep(0.5)
    code = os.waitstatus_to_exitcode(status)
    record = {"wall_s": round(time.monotonic() - start, 1), "cpu_s": round(usage.ru_utime + usage.ru_stime, 1),
              "exit": code, "interrupted": interrupted}
    with open(a.record, "w") as f:
        json.dump(record, f)
    return 0 if interrupted and code in (0, 72, -signal.SIGINT) else (code if code >= 0 else 128 - code)


if __name__ == "__main__":
    sys.exit(main())
