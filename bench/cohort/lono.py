#!/usr/bin/python3
"""Leave-one-normal-out: how many false foci the comparison draws in subjects that have none
(issue 35; docs/cohort.md, "Sharper elements, a relative extent, and false foci in normals").

Each normal's element table is compared, with `vpm compare`, against the reference of all the
other normals, with exactly the options (threshold, clusters, hysteresis, test, smoothing,
normalisation, sign) of a patient's comparison the workflow wrote (RESULTS/compare/*_FEATURE.json),
so the count is that of the workflow's own settings. Every cluster found is a false focus.
Reported: the clusters per normal, their total and the rate per 10 normals.

--calibrate RATE: the comparisons run once at --min-cluster 1 and every cluster's candidate count
(the elements at or beyond the cut) tells which clusters each larger min_cluster keeps, so the
false-cluster rate of every min_cluster follows from one pass; reported: that curve and the
smallest min_cluster at or under RATE false clusters per 10 normals (a cluster-extent threshold
set by the normals themselves, as a permutation test over them would).

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
    sidecars = sorted(glob.glob(os.path.join(glob.escape(results), "compare", f"*_{feature}.json")))
    if not sidecars:
        fail(os.path.join(results, "compare"), f"no comparison sidecar *_{feature}.json")
    try:
        with open(sidecars[0]) as f:
            side = json.load(f)
        o, ref = side["options"], side["reference"]
        sign = {-1: "hypo", 1: "hyper", 0: "both"}[int(o["sign"])]
        args = ["--normalisation", str(ref["normalisation"]), "--smooth", str(int(ref["smoothing"])),
                "--min-cluster", str(int(o["min_cluster"])), "--test", str(o["test"]), "--sign", sign]
        if float(o.get("fdr_q", 0)) > 0:
            args += ["--fdr", repr(float(o["fdr_q"]))]
        else:
            args += ["--threshold", repr(float(o["threshold"]))]
        for key, flag in (("extend", "--extend"), ("peak", "--peak")):
            if float(o.get(key, 0)) > 0:
                args += [flag, repr(float(o[key]))]
        return args, sidecars[0]
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(sidecars[0], f"not a comparison sidecar ({e})")


def one(vpm, tables, feature, options, normal, scratch):
    others = ",".join(t for t in tables if t != normal)
    out = os.path.join(scratch, os.path.basename(normal))
    argv = [vpm, "compare", "--normals", others, "--patient", normal, "--feature", feature, *options, "-o", out]
    r = subprocess.run(argv, capture_output=True, text=True)
    if r.returncode != 0:
        fail(normal, f"vpm compare exit {r.returncode}: {r.stderr.strip()[-300:]}")
    with open(os.path.splitext(out)[0] + ".json") as f:
        clusters = json.load(f)["result"]["clusters"]
    return {"normal": os.path.basename(normal), "clusters": len(clusters), "elements": [c["elements"] for c in clusters],
            "candidates": [c["candidates"] for c in clusters], "peak_z": [c["peak_z"] for c in clusters]}


def with_min_cluster(options, m):
    out = list(options)
    out[out.index("--min-cluster") + 1] = str(m)
    return out


def calibration(rows, normals, rate, used):
    """False clusters per 10 normals for every min_cluster up to the largest candidate count."""
    sizes = sorted(c for r in rows for c in r["candidates"])
    curve = [{"min_cluster": m, "false_clusters": sum(c >= m for c in sizes),
              "per_10_normals": 10.0 * sum(c >= m for c in sizes) / normals}
             for m in range(1, (sizes[-1] if sizes else 0) + 2)]
    meets = [p["min_cluster"] for p in curve if p["per_10_normals"] <= rate]
    return {"rate": rate, "min_cluster": meets[0], "workflow_min_cluster": used, "curve": curve}


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
    if a.calibrate is not None:
        if not a.calibrate >= 0:
            fail("--calibrate", f"{a.calibrate}: must be >= 0")
        options = with_min_cluster(options, 1)
    tables_dir = a.tables or os.path.join(a.results, "tables")
    tables = sorted(glob.glob(os.path.join(glob.escape(tables_dir), f"{a.normals_glob}_{a.feature}.tsv")))
    if len(tables) < 4:
        fail(tables_dir, f"{len(tables)} normals' tables ({a.normals_glob}_{a.feature}.tsv); needs at least 4")
    start = time.time()
    with tempfile.TemporaryDirectory(prefix="vpm-lono-") as scratch, ThreadPoolExecutor(a.jobs) as pool:
        rows = list(pool.map(lambda t: one(a.vpm, tables, a.feature, options, t, scratch), tables))
    if a.calibrate is not None:
        cal = calibration(rows, len(tables), a.calibrate, used)
        for r in rows:  # the workflow's own min_cluster, from the same pass
            keep = [i for i, c in enumerate(r["candidates"]) if c >= used]
            r.update({k: [r[k][i] for i in keep] for k in ("elements", "candidates", "peak_z")}, clusters=len(keep))
        options = with_min_cluster(options, used)
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
