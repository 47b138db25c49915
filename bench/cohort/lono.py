#!/usr/bin/python3
"""Leave-one-normal-out: how many false foci the comparison draws in subjects that have none
(issue 35; bench/results/cohort_sharper/).

Each normal's element table is compared, with `vpm compare`, against the reference of all the
other normals, with exactly the options (threshold, clusters, hysteresis, test, smoothing,
normalisation, sign, covariates and their participants table, image covariate) of a patient's comparison the
workflow wrote (RESULTS/compare/*_FEATURE.json), so the count is that of the workflow's own
settings. Every cluster found is a false focus.
Reported: the clusters per normal, their total and the rate per 10 normals.

--calibrate RATE: also `vpm calibrate` on the same tables with the same options (one pass at
min_cluster 1 whose clusters' candidate counts give the false-cluster rate of every min_cluster;
vpm/calibration.hpp); reported: that curve and the smallest min_cluster at or under RATE false
clusters per 10 normals (a cluster-extent threshold set by the normals themselves, as a
permutation test over them would). The workflow runs the same with compare.min_cluster: auto.

Usage: lono.py --results DIR [--feature pet] [--tables DIR] [--vpm PATH] [--jobs 2] [--calibrate RATE]
              [--out-json PATH]
  --tables: the element tables (default RESULTS/tables); the options are still read from RESULTS.
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor


def fail(path, problem):
    print(f"lono.py: {path}: {problem}", file=sys.stderr)
    sys.exit(2)


def workflow_options(results, feature):
    """The compare options and smoothing of the first patient's sidecar, as CLI arguments."""
    sidecars = sorted(p for p in glob.glob(os.path.join(glob.escape(results), "compare", f"*_{feature}.json"))
                      if not os.path.basename(p).startswith("calibration_"))  # vpm calibrate's, not a comparison
    if not sidecars:
        fail(os.path.join(results, "compare"), f"no comparison sidecar *_{feature}.json")
    try:
        with open(sidecars[0]) as f:
            side = json.load(f)
        o, ref = side["options"], side["reference"]
        sign = {-1: "hypo", 1: "hyper", 0: "both"}[int(o["sign"])]
        args = ["--normalisation", str(ref["normalisation"]), "--smooth", str(int(ref["smoothing"])),
                "--shrink", repr(float(ref.get("shrinkage", 0))),
                "--min-cluster", str(int(o["min_cluster"])), "--test", str(o["test"]), "--sign", sign]
        if float(o.get("fdr_q", 0)) > 0:
            args += ["--fdr", repr(float(o["fdr_q"]))]
        else:
            args += ["--threshold", repr(float(o["threshold"]))]
        for key, flag in (("extend", "--extend"), ("peak", "--peak"), ("relative_extent", "--relative-extent")):
            if float(o.get(key, 0)) > 0:
                args += [flag, repr(float(o[key]))]
        cov = ref.get("covariates")  # compare.covariates: the same model, from the same table
        if cov:
            args += ["--covariates", ",".join(str(c) for c in cov["names"]), "--participants", str(cov["table"])]
        if ref.get("image_covariate"):  # compare.image_covariate
            args += ["--image-covariate", str(ref["image_covariate"])]
        return args, sidecars[0]
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(sidecars[0], f"not a comparison sidecar ({e})")


def one(vpm, tables, feature, options, normal, scratch):
    others = ",".join(t for t in tables if t != normal)
    out = os.path.join(scratch, os.path.splitext(os.path.basename(normal))[0] + ".tsv")
    argv = [vpm, "compare", "--normals", others, "--patient", normal, "--feature", feature, *options, "-o", out]
    r = subprocess.run(argv, capture_output=True, text=True)
    if r.returncode != 0:
        fail(normal, f"vpm compare exit {r.returncode}: {r.stderr.strip()[-300:]}")
    with open(os.path.splitext(out)[0] + ".json") as f:
        clusters = json.load(f)["result"]["clusters"]
    return {"normal": os.path.basename(normal), "clusters": len(clusters), "elements": [c["elements"] for c in clusters],
            "candidates": [c["candidates"] for c in clusters], "peak_z": [c["peak_z"] for c in clusters]}


def without_min_cluster(options):
    i = options.index("--min-cluster")
    return options[:i] + options[i + 2:]


def vpm_calibration(vpm, tables, feature, options, rate, used, scratch):
    """`vpm calibrate` over the tables with the comparisons' options: its curve and choice."""
    out = os.path.join(scratch, "calibration.json")
    argv = [vpm, "calibrate", "--normals", ",".join(tables), "--feature", feature, *without_min_cluster(options),
            "--rate", repr(rate), "-o", out]
    r = subprocess.run(argv, capture_output=True, text=True)
    if r.returncode not in (0, 3):  # 3: no min_cluster reaches the rate (the JSON says how far it got)
        fail("vpm calibrate", f"exit {r.returncode}: {r.stderr.strip()[-300:]}")
    with open(out) as f:
        j = json.load(f)
    return {"rate": rate, "min_cluster": j["min_cluster"], "workflow_min_cluster": used, "curve": j["curve"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--results", required=True)
    ap.add_argument("--feature", default="pet")
    ap.add_argument("--tables")
    ap.add_argument("--normals-glob", default="sub-N*", help="which tables are normals (default sub-N*)")
    ap.add_argument("--vpm", default="vpm")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--calibrate", type=float, metavar="RATE",
                    help="the smallest min_cluster with at most RATE false clusters per 10 normals")
    ap.add_argument("--out-json")
    a = ap.parse_args()
    options, source = workflow_options(a.results, a.feature)
    used = int(options[options.index("--min-cluster") + 1])
    if a.calibrate is not None and not a.calibrate >= 0:
        fail("--calibrate", f"{a.calibrate}: must be >= 0")
    tables_dir = a.tables or os.path.join(a.results, "tables")
    # the workflow's HDF5 tables, or TSV exports
    tables = sorted(glob.glob(os.path.join(glob.escape(tables_dir), f"{a.normals_glob}_{a.feature}.h5")) or
                    glob.glob(os.path.join(glob.escape(tables_dir), f"{a.normals_glob}_{a.feature}.tsv")))
    if len(tables) < 4:
        fail(tables_dir, f"{len(tables)} normals' tables ({a.normals_glob}_{a.feature}.h5 or .tsv); needs at least 4")
    start = time.time()
    with tempfile.TemporaryDirectory(prefix="vpm-lono-") as scratch, ThreadPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(lambda t: one(a.vpm, tables, a.feature, options, t, scratch), tables))
        if a.calibrate is not None:
            cal = vpm_calibration(a.vpm, tables, a.feature, options, a.calibrate, used, scratch)
    total = sum(r["clusters"] for r in rows)
    report = {"options": options, "options_from": source, "tables": tables_dir, "normals": len(tables),
              "false_clusters": total, "per_10_normals": 10.0 * total / len(tables),
              "normals_with_a_cluster": sum(r["clusters"] > 0 for r in rows), "per_normal": rows,
              "seconds": round(time.time() - start, 1)}
    if a.calibrate is not None:
        report["calibration"] = cal
    if a.out_json:
        with open(a.out_json, "w") as f:
            json.dump(report, f, indent=1)
            f.write("\n")
    print(f"leave-one-normal-out: {total} false clusters in {len(tables)} normals "
          f"({report['per_10_normals']:.2f} per 10 normals; {report['normals_with_a_cluster']} normals with one); "
          f"options {' '.join(options)}; {report['seconds']} s")
    if a.calibrate is not None:
        print(f"calibration: min_cluster {cal['min_cluster']} gives at most {a.calibrate:g} per 10 normals; "
              + ", ".join(f"{p['min_cluster']}: {p['per_10_normals']:.2f}" for p in cal["curve"][:80]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
