#!/usr/bin/env python3
"""The scale benchmark of the collective analysis (docs/cohort.md "Cohorts of thousands").

Element tables of N synthetic normals are made directly (vpm_bench_cohort_scale: smooth fields
plus noise per element, level-6 graded elements by default, PET and T1w), then the workflow's
group-level steps run on them with the workflow's defaults (image covariate t1w, shrinkage 0.8,
hysteresis 2.25, relative extent 0.22, decreases only, calibrated cluster size and peak):

  reference  vpm reference --normals @LIST            (one streaming pass over the tables)
  calibrate  vpm calibrate --reference SUMS --normals @LIST   (leave-one-out from the totals)
  compare    vpm compare --reference SUMS --patient P --min-cluster-from CAL

Each step is timed as a whole process (wall seconds) with its peak resident memory (the
kernel's ru_maxrss of the child), over --runs runs (the median is reported); a table's size
and read time (vpm_bench_cohort_scale --read, median of 5) are recorded once. Writes a JSON
report and prints a Markdown table.

  bench/cohort_scale/run.py --build build --data /tmp/scale --sizes 50,300,1000 --runs 3 --json out.json
"""
import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time

COMPARE = ["--feature", "pet", "--image-covariate", "t1w", "--shrink", "0.8", "--extend", "2.25",
           "--relative-extent", "0.22", "--sign", "hypo", "--threshold", "3"]
RECIPE = ["--feature", "pet", "--image-covariate", "t1w"]


def timed(cmd, log):
    """Runs cmd; returns (wall seconds, peak RSS in MB). Raises on a non-zero exit."""
    start = time.monotonic()
    with open(log, "a") as out:
        out.write("$ " + " ".join(cmd) + "\n")
        out.flush()
        proc = subprocess.Popen(cmd, stdout=out, stderr=out)
        _, status, usage = os.wait4(proc.pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"cohort_scale: {' '.join(cmd[:2])} exited {code}; see {log}")
    return wall, usage.ru_maxrss / 1024.0


def machine():
    cpu = ""
    try:
        cpu = next(l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"cpus": os.cpu_count(), "cpu": cpu, "memory_gb": round(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30, 1),
            "system": platform.platform()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default="build")
    ap.add_argument("--data", required=True, help="where the tables are made (kept between runs)")
    ap.add_argument("--sizes", default="50,300,1000")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--level", type=int, default=6)
    ap.add_argument("--json", default="")
    a = ap.parse_args()
    vpm = os.path.join(a.build, "vpm")
    gen = os.path.join(a.build, "bench", "vpm_bench_cohort_scale")
    tables = os.path.join(a.data, f"level{a.level}")
    log = os.path.join(a.data, "log.txt")
    os.makedirs(tables, exist_ok=True)
    report = {"machine": machine(), "level": a.level, "runs": a.runs, "compare_options": COMPARE, "sizes": []}
    for n in [int(x) for x in a.sizes.split(",") if x]:
        made = timed([gen, "--out", tables, "--normals", str(n), "--patients", "1", "--level", str(a.level)], log)
        normals = sorted(os.path.join(tables, f) for f in os.listdir(tables) if f.startswith("sub-N"))[:n]
        listed = os.path.join(a.data, f"normals_{n}.txt")
        with open(listed, "w") as f:
            f.writelines(p + "\n" for p in normals)
        patient = os.path.join(tables, "sub-P000_pet.h5")
        sums, cal, out = (os.path.join(a.data, f"{x}_{n}.{ext}") for x, ext in (("sums", "h5"), ("cal", "json"), ("compare", "tsv")))
        steps = {
            "reference": [vpm, "reference", "--normals", "@" + listed, *RECIPE, "-o", sums, "--quiet"],
            "calibrate": [vpm, "calibrate", "--reference", sums, "--normals", "@" + listed, *COMPARE, "--peak", "auto",
                          "--rate", "1", "-o", cal, "--quiet"],
            "compare": [vpm, "compare", "--reference", sums, "--patient", patient, *COMPARE, "--min-cluster-from", cal,
                        "-o", out, "--quiet"],
        }
        row = {"normals": n, "generated_s": round(made[0], 1), "steps": {}}
        for name, cmd in steps.items():
            runs = [timed(cmd, log) for _ in range(a.runs)]
            row["steps"][name] = {"seconds": [round(w, 2) for w, _ in runs], "peak_mb": [round(m) for _, m in runs],
                                  "median_s": round(statistics.median(w for w, _ in runs), 2),
                                  "median_peak_mb": round(statistics.median(m for _, m in runs))}
            print(f"N={n} {name}: {row['steps'][name]['median_s']} s, {row['steps'][name]['median_peak_mb']} MB", flush=True)
        row["calibration"] = {k: json.load(open(cal))[k] for k in ("min_cluster", "peak", "normals")}
        row["foci"] = len(json.load(open(os.path.splitext(out)[0] + ".json"))["result"]["clusters"])
        report["sizes"].append(row)
    read = subprocess.run([gen, "--read", patient], capture_output=True, text=True, check=True).stdout
    report["table"] = {"bytes": os.path.getsize(patient), **json.loads(read)}
    print("\n| normals | reference | calibrate (leave-one-out) | compare one patient |")
    print("|---|---|---|---|")
    for r in report["sizes"]:
        cells = [f"{r['steps'][s]['median_s']} s, {r['steps'][s]['median_peak_mb']} MB" for s in ("reference", "calibrate", "compare")]
        print(f"| {r['normals']:,} | " + " | ".join(cells) + " |")
    print(f"\ntable: {report['table']['bytes'] / 1e6:.1f} MB, read in {report['table']['read_median_s']} s (median of 5)")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(report, f, indent=2)


if __name__ == "__main__":
    main()
