#!/usr/bin/python3
"""Summarises a cohort run (bench/cohort/run.sh): wall time and peak memory of every workflow
rule from Snakemake's benchmark files (RESULTS/benchmarks/*.tsv: s, max_rss in MB), the whole
workflow's wall time, and the foci scores of RESULTS/evaluation.json, as JSON and markdown.

Usage: summary.py --results DIR --synth-seconds S --workflow-seconds S --cores N
                  [--out-json PATH] [--out-md PATH]
"""
import argparse
import csv
import glob
import json
import os
import platform
import statistics
import sys
import time


def rule_stats(results):
    per_rule = {}
    for path in sorted(glob.glob(os.path.join(results, "benchmarks", "*.tsv"))):
        rule = os.path.basename(path)[:-4].split("_", 1)[-1] if "sub-" in path else os.path.basename(path)[:-4]
        if rule.endswith("_compare"):  # {sub}_{feature}_compare: one comparison per feature
            rule = "compare"
        with open(path, newline="") as f:
            for row in csv.DictReader(f, delimiter="\t"):
                rss = row.get("max_rss", "-")
                per_rule.setdefault(rule, []).append((float(row["s"]), float(rss) if rss not in ("-", "NA", "") else 0.0))
    out = {}
    for rule, v in per_rule.items():
        secs = [s for s, _ in v]
        out[rule] = {"jobs": len(v), "median_s": statistics.median(secs), "max_s": max(secs), "total_s": sum(secs),
                     "max_rss_mb": max(m for _, m in v)}
    return out


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", required=True)
    ap.add_argument("--synth-seconds", type=float, required=True)
    ap.add_argument("--workflow-seconds", type=float, required=True)
    ap.add_argument("--cores", type=int, required=True)
    ap.add_argument("--out-json")
    ap.add_argument("--out-md")
    a = ap.parse_args()
    ev_path = os.path.join(a.results, "evaluation.json")
    if not os.path.exists(ev_path):
        print(f"summary.py: {ev_path}: not found (did the workflow finish?)", file=sys.stderr)
        return 2
    ev = json.load(open(ev_path))
    rules = rule_stats(a.results)
    s = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "machine": platform.node(),
         "cpus": os.cpu_count(), "cores": a.cores, "synth_seconds": a.synth_seconds,
         "workflow_seconds": a.workflow_seconds, "patients": len(ev["patients"]), "rules": rules,
         "evaluation": ev["summary"], "threshold": ev.get("threshold")}
    lines = [f"Workflow wall time {a.workflow_seconds:.0f} s on {a.cores} cores for {len(ev['patients'])} patients "
             f"and the normals (synthesis {a.synth_seconds:.0f} s, not included), {s['date']}.", "",
             "| rule | jobs | median s | max s | peak memory MB |", "|---|---|---|---|---|"]
    for rule in ("template_mesh", "template_map", "mesh", "map", "register", "sample", "compare", "view"):
        if rule in rules:
            r = rules[rule]
            lines.append(f"| {rule} | {r['jobs']} | {r['median_s']:.2f} | {r['max_s']:.2f} | {r['max_rss_mb']:.0f} |")
    lines.append("")
    md_eval = os.path.join(a.results, "evaluation.md")
    if os.path.exists(md_eval):
        lines.append(open(md_eval).read())
    md = "\n".join(lines) + "\n"
    if a.out_json:
        with open(a.out_json, "w") as f:
            json.dump(s, f, indent=1)
    if a.out_md:
        with open(a.out_md, "w") as f:
            f.write(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
