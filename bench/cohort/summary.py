#!/usr/bin/python3
"""Summarises a cohort run (bench/cohort/run.sh): wall time and peak memory of every workflow
rule from Snakemake's benchmark files (RESULTS/benchmarks/*.tsv: s, max_rss in MB), the whole
workflow's wall time, and the foci scores of RESULTS/evaluation.json, as JSON and markdown.

The individual-analysis row beside vpm is the elastix peer (bench/cohort/voxelwise_elastix.py,
RESULTS/peer_elastix/evaluation.json: its default setting in the tables, any further settings
pooled below them, its time per subject and, given --peer-seconds, its wall time) when that file
exists; otherwise (older results, or elastix not on PATH) evaluate.py's affine baseline, as in
RESULTS/evaluation.md, with a note. --individual affine always shows the affine baseline, without
the note; --individual elastix requires the peer.

Usage: summary.py --results DIR --synth-seconds S --workflow-seconds S --cores N
                  [--peer-seconds S] [--individual auto|elastix|affine] [--out-json PATH] [--out-md PATH]
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evaluate  # noqa: E402


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


def peer_tables(ev, peer, peer_path):
    """Markdown of vpm beside the elastix peer's default setting, then its other settings pooled."""
    settings = peer["settings"]
    chosen = next((s for s in settings if s["setting"] == peer.get("default_setting")), settings[0])
    rows = {r["participant_id"]: r for r in chosen["patients"]}
    missing = [r["participant_id"] for r in ev["patients"] if r["participant_id"] not in rows]
    if missing:
        print(f"summary.py: {peer_path}: no scores for {', '.join(missing)}", file=sys.stderr)
        sys.exit(2)
    report = {"patients": [{"participant_id": r["participant_id"], "vpm": r["vpm"], "peer": rows[r["participant_id"]]}
                           for r in ev["patients"]],
              "threshold": ev.get("threshold"), "summary": {"vpm": ev["summary"]["vpm"], "peer": chosen["summary"]}}
    md = evaluate.markdown(report, ("vpm", "peer"), {"vpm": evaluate.NAMES["vpm"], "peer": chosen["label"]})
    others = [s for s in settings if s is not chosen]
    if others:
        free = [evaluate.foci_free(s["summary"], s["patients"]) for s in others]
        nfree = max(n for n, _ in free)
        md += ("\nFurther settings of the elastix peer, pooled:\n\n| setting | volume overlap (sensitivity) | "
               "precision | Dice | foci found | false-positive clusters |"
               + (f" of them in the {nfree} foci-free patients |" if nfree else "")
               + "\n|---|---|---|---|---|---|" + ("---|" if nfree else "") + "\n")
        for s, (_, fc) in zip(others, free):
            p = s["summary"]["pooled"]
            md += (f"| {s['label']} | {evaluate.pct(p['sensitivity'])} | {evaluate.pct(p['precision'])} | "
                   f"{evaluate.pct(p['dice'])} | {s['summary']['foci_found']}/{s['summary']['foci_planted']} | "
                   f"{s['summary']['false_positive_clusters']} |" + (f" {fc} |" if nfree else "") + "\n")
    return md


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--results", required=True)
    ap.add_argument("--synth-seconds", type=float, required=True)
    ap.add_argument("--workflow-seconds", type=float, required=True)
    ap.add_argument("--cores", type=int, required=True)
    ap.add_argument("--peer-seconds", type=float, help="wall time of bench/cohort/voxelwise_elastix.py")
    ap.add_argument("--individual", choices=("auto", "elastix", "affine"), default="auto",
                    help="the individual-analysis row: the elastix peer (auto: when its results exist) or "
                         "evaluate.py's affine baseline")
    ap.add_argument("--out-json")
    ap.add_argument("--out-md")
    a = ap.parse_args()
    ev_path = os.path.join(a.results, "evaluation.json")
    if not os.path.exists(ev_path):
        print(f"summary.py: {ev_path}: not found (did the workflow finish?)", file=sys.stderr)
        return 2
    ev = json.load(open(ev_path))
    peer_path = os.path.join(a.results, "peer_elastix", "evaluation.json")
    peer = None
    if a.individual == "elastix" or (a.individual == "auto" and os.path.exists(peer_path)):
        if not os.path.exists(peer_path):
            print(f"summary.py: {peer_path}: not found (run bench/cohort/voxelwise_elastix.py)", file=sys.stderr)
            return 2
        peer = json.load(open(peer_path))
    rules = rule_stats(a.results)
    s = {"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "machine": platform.node(),
         "cpus": os.cpu_count(), "cores": a.cores, "synth_seconds": a.synth_seconds,
         "workflow_seconds": a.workflow_seconds, "patients": len(ev["patients"]), "rules": rules,
         "evaluation": ev["summary"], "threshold": ev.get("threshold"),
         "individual": "elastix" if peer else "affine"}
    if peer:
        s["peer_elastix"] = {"wall_seconds": a.peer_seconds, "jobs": peer["seconds"]["jobs"],
                             "median_s": peer["seconds"]["median_s"], "max_s": peer["seconds"]["max_s"],
                             "default_setting": peer.get("default_setting"),
                             "settings": [{k: x[k] for k in ("setting", "label", "summary")} for x in peer["settings"]]}
    lines = [f"Workflow wall time {a.workflow_seconds:.0f} s on {a.cores} cores for {len(ev['patients'])} patients "
             f"and the normals (synthesis {a.synth_seconds:.0f} s, not included), {s['date']}.", "",
             "| rule | jobs | median s | max s | peak memory MB |", "|---|---|---|---|---|"]
    for rule in ("template_mesh", "template_map", "mesh", "map", "register", "sample", "compare", "view"):
        if rule in rules:
            r = rules[rule]
            lines.append(f"| {rule} | {r['jobs']} | {r['median_s']:.2f} | {r['max_s']:.2f} | {r['max_rss_mb']:.0f} |")
    lines.append("")
    if peer:
        sec = peer["seconds"]
        wall = f"wall time {a.peer_seconds:.0f} s, " if a.peer_seconds is not None else ""
        lines += [f"Individual analysis: voxel-wise after elastix (bench/cohort/voxelwise_elastix.py), {wall}"
                  f"{sec['jobs']} subjects at a time, per subject (elastix + transformix + warping) median "
                  f"{sec['median_s']:.0f} s, max {sec['max_s']:.0f} s; not in the workflow's time.", "",
                  peer_tables(ev, peer, peer_path)]
    else:
        if a.individual == "auto":
            lines += [f"Individual analysis: voxel-wise after affine (evaluate.py's baseline): no {peer_path} "
                      "(elastix not on PATH, or bench/cohort/voxelwise_elastix.py not run).", ""]
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
