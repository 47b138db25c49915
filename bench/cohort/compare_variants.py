#!/usr/bin/python3
"""The foci of a finished cohort run re-drawn with other `vpm compare` settings, each scored
against the planted truth as bench/cohort/evaluate.py scores the workflow's (issue 35;
bench/results/cohort_relative_extent/). The registered meshes and element tables are the run's own: only the
comparison changes, so a setting costs seconds per patient instead of a workflow run.

Every variant starts from the options of the run's own comparisons (a patient's sidecar, read as
bench/cohort/lono.py reads it) and overrides the flags it names; `--tables NAME DIR` gives a
variant other element tables (e.g. `vpm sample --level 5` of the same registered meshes), and a flag
given the value "-" is dropped (e.g. `--image-covariate -`).
Writes OUT/NAME/compare/ (the comparisons) and OUT/variants.json, and prints a markdown table
(pooled over the patients: volume overlap, precision, Dice, foci found, false clusters, and the
false clusters in the foci-free patients).

Usage: compare_variants.py --bids DIR --results DIR --out DIR --variant NAME "OPTIONS" [...]
                           [--tables NAME DIR] [--vpm PATH] [--jobs 2]
Exit 2 (one line on stderr) on a missing input or a failed comparison.
"""
import argparse
import json
import os
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import evaluate  # noqa: E402
import lono  # noqa: E402


def merged(base, extra):
    """`base` (flag value pairs) with the flags of `extra` replaced or added (a value "-" drops the flag)."""
    opts, order = {}, []
    for args in (base, extra):
        if len(args) % 2:
            evaluate.fail("--variant", f"'{' '.join(args)}': every flag takes one value")
        for flag, value in zip(args[::2], args[1::2]):
            if flag not in opts:
                order.append(flag)
            opts[flag] = value
    return [x for f in order if opts[f] != "-" for x in (f, opts[f])]


def compare_one(a, name, options, tables, sid):
    """One patient's comparison for one variant; returns (detected, truth) voxel arrays."""
    def table(sid):  # the workflow's HDF5 table, or a TSV export
        h5 = os.path.join(tables, f"{sid}_pet.h5")
        return h5 if os.path.exists(h5) else os.path.join(tables, f"{sid}_pet.tsv")
    normals = ",".join(table(n) for n in a.normals)
    out = os.path.join(a.out, name, "compare", f"{sid}_pet.tsv")
    argv = [a.vpm, "compare", "--normals", normals, "--patient", table(sid),
            "--feature", "pet", *options, "--mesh", os.path.join(a.results, "subjects", sid, f"{sid}_registered.vtu"),
            "--image", os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz"), "-o", out, "--quiet"]
    r = subprocess.run(argv, capture_output=True, text=True)
    if r.returncode != 0:
        evaluate.fail(out, f"vpm compare exit {r.returncode}: {r.stderr.strip()[-300:]}")
    det, _ = evaluate.load(os.path.join(a.out, name, "compare", f"{sid}_pet_foci.nii.gz"))
    truth, _ = evaluate.load(os.path.join(a.bids, "derivatives", "truth", f"{sid}_foci.nii.gz"))
    return evaluate.score(det, truth)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bids", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--variant", nargs=2, action="append", required=True, metavar=("NAME", "OPTIONS"))
    ap.add_argument("--tables", nargs=2, action="append", default=[], metavar=("NAME", "DIR"))
    ap.add_argument("--vpm", default="vpm")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    a.normals, patients = evaluate.read_participants(a.bids)
    base, sidecar = lono.workflow_options(a.results, "pet")
    tables = dict(a.tables)
    report = {"results": a.results, "base_options": base, "base_sidecar": sidecar, "variants": []}
    print("| variant | compare options | volume overlap | precision | Dice | foci found | false clusters | in foci-free |")
    print("|---|---|---|---|---|---|---|---|")
    for name, extra in a.variant:
        options = merged(base, shlex.split(extra))
        where = tables.get(name, os.path.join(a.results, "tables"))
        os.makedirs(os.path.join(a.out, name, "compare"), exist_ok=True)
        with ThreadPoolExecutor(max(1, a.jobs)) as pool:
            scores = list(pool.map(lambda sid: compare_one(a, name, options, where, sid), patients))
        summary = evaluate.summarise(scores)
        p = summary["pooled"]
        print(f"| {name} | {' '.join(shlex.split(extra))} | {evaluate.pct(p['sensitivity'])} | "
              f"{evaluate.pct(p['precision'])} | {evaluate.pct(p['dice'])} | {summary['foci_found']}/"
              f"{summary['foci_planted']} | {summary['false_positive_clusters']} | "
              f"{summary.get('false_clusters_in_foci_free', '')} |", flush=True)
        report["variants"].append({"name": name, "options": options, "tables": where, "summary": summary,
                                   "patients": dict(zip(patients, scores))})
    with open(os.path.join(a.out, "variants.json"), "w") as f:
        json.dump(report, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
