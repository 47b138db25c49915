#!/usr/bin/env python3
"""Summary of a scripts/fuzz.sh run as JSON on stdout: per target the executions, the wall and
CPU seconds (user + system, from fuzz_run.py's cost.json), the coverage (cov: instrumented edges
reached; ft: libFuzzer's features), the corpus (inputs and bytes), the findings (crash-,
timeout-, leak-, oom- and slow-unit- files) and the first error line of the log.
Usage: fuzz_summary.py FUZZ_OUT CORPUS TARGET...
"""
import json
import pathlib
import re
import sys


def target_summary(out, corpus, target):
    log = (out / target / "log").read_text(errors="replace") if (out / target / "log").exists() else ""
    stats = dict(re.findall(r"^stat::(\w+):\s+(\d+)", log, re.M))
    status = re.findall(r"^#(\d+)\s+\w+\s+cov: (\d+) ft: (\d+) corp: (\d+)/(\d+)(\w+)", log, re.M)
    files = [p for p in (corpus / target).iterdir() if p.is_file()] if (corpus / target).is_dir() else []
    findings = sorted(p.name for p in (out / target).iterdir()
                      if p.name.split("-")[0] in ("crash", "timeout", "leak", "oom", "slow"))
    error = next((line for line in log.splitlines()
                  if line.startswith(("==", "SUMMARY", "vpm fuzz:")) or "runtime error" in line), "")
    last = status[-1] if status else ("0",) * 6
    cost_file = out / target / "cost.json"
    cost = json.loads(cost_file.read_text()) if cost_file.exists() else {}
    wall, cpu = cost.get("wall_s"), cost.get("cpu_s")
    return {
        "executions": int(stats.get("number_of_executed_units", last[0])),
        "execs_per_s": int(stats.get("average_exec_per_sec", 0)),
        "wall_s": wall,
        "cpu_s": cpu,
        "cov": int(last[1]),
        "ft": int(last[2]),
        "corpus_inputs": len(files),
        "corpus_bytes": sum(p.stat().st_size for p in files),
        "peak_rss_mb": int(stats.get("peak_rss_mb", 0)),
        "findings": findings,
        "error": error,
    }


def main():
    out, corpus = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    targets = {t: target_summary(out, corpus, t) for t in sys.argv[3:]}
    total = {"executions": sum(t["executions"] for t in targets.values()),
             "cpu_s": round(sum(t["cpu_s"] or 0 for t in targets.values()), 1),
             "findings": sum(len(t["findings"]) for t in targets.values())}
    json.dump({"targets": targets, "total": total}, sys.stdout, indent=2)
    print()


if __name__ == "__main__":
    main()
