#!/usr/bin/python3
"""vpm's registration against elastix on the same synthetic pairs, scored the same way.

Each pair is Colin27 and a copy deformed by `vpm_bench_pairs --seed S --max-rotation DEG
--incompressible` (a volume-preserving flow plus a rotation; seed 0 without --incompressible
and rotation is the demo's own pair). For each pair:

* vpm: `vpm_bench_pairs` (bench/pairs.cpp, `vpm demo`'s pipeline) meshes and maps both brains, registers the subject to Colin27 (caudate and
  thalamus held out of the landmarks and forces) and scores the registration; from its report
  this script takes the held-out Dice in the subject's image space (Colin27's atlas carried onto
  the subject's voxels through the maps) and in the ball, the registration's volume change
  (tet mean |r - 1|, folds), the ideal registration's Dice (from the known deformation) and the
  time of mesh + map + register of the subject.
* elastix (Debian's, bench only): affine then cubic B-spline (Mattes MI, 4 levels, 8 mm final
  grid; affine.txt, bspline.txt beside this script) with the subject as the fixed image and
  Colin27 as the moving one; transformix carries Colin27's atlas onto the subject's voxels
  (nearest neighbour) and writes the transform's Jacobian determinant. Scored by the same Dice
  (the subject's own atlas against the carried one, per held-out label) and by mean |det J - 1|
  over the subject's brain (T1 > 0).

usage: bench/register_peers/run.py [--pairs build/bench/vpm_bench_pairs] [--seeds 1,2,3,4,5] [--demo-pair]
         [--target-vertices N[,N...] | --configs "N[:OPTIONS][;N[:OPTIONS]...]"] [--max-rotation 10]
         [--threads 2] [--no-elastix]
         [--out build/bench-register-peers] [--json FILE]
Prints a table per pair and the medians; writes FILE (default OUT/register_peers.json).
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

import nibabel
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
HELD_OUT = [(71, "Caudate_L"), (72, "Caudate_R"), (77, "Thalamus_L"), (78, "Thalamus_R")]
DATA = "/usr/share/mricron/templates"


def run(cmd, log):
    """Runs cmd (a list: no shell) with its output in the file `log`; returns the seconds."""
    t0 = time.monotonic()
    with open(log, "w") as f:
        r = subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        sys.exit(f"register_peers: {cmd[0]} exited {r.returncode}; see {log}")
    return time.monotonic() - t0


def dice(a, b, label):
    x, y = a == label, b == label
    s = int(x.sum()) + int(y.sum())
    return 2.0 * int((x & y).sum()) / s if s else 1.0


def vpm_pair(args, seed, vertices, extra, tag, out):
    d = os.path.join(out, f"vpm_v{vertices}{tag}_s{seed}")
    cmd = [args.pairs, "--out", d, "--seed", str(seed), "--target-vertices", str(vertices)] + extra
    if seed > 0:
        cmd += ["--incompressible", "--max-rotation", str(args.max_rotation)]
    wall = run(cmd, d + ".log")
    rep = json.load(open(os.path.join(d, "demo.json")))
    held = rep["overlap"]["held_out"]
    ideal = rep["ideal"]["held_out"]
    subj = rep["subjects"]["subject"]
    reg = rep["registration"]
    return d, {
        "method": f"vpm {vertices}{tag}",
        "target_vertices": vertices,
        "vpm_options": extra,
        "tets": subj["tets"],
        "dice_subject": [h["dice_subject_after"] for h in held],
        "dice_ball": [h["dice_image_after"] for h in held],
        "ideal_dice_subject": [h["dice_subject"] for h in ideal],
        "ideal_dice_ball": [h["dice_image"] for h in ideal],
        "volume_change": reg["tet_volume_ratio"]["mean_abs_dev"],
        "folds": reg["inverted_tets"],
        "seconds": subj["mesh_seconds"] + subj["map_seconds"] + rep["timings_s"]["register"],
        "seconds_register": rep["timings_s"]["register"],
        "seconds_demo": wall,
    }


def elastix_pair(args, seed, pair_dir, out):
    d = os.path.join(out, f"elastix_s{seed}")
    os.makedirs(d, exist_ok=True)
    fixed = os.path.join(pair_dir, "subject_t1.nii.gz")
    seconds = run(["elastix", "-f", fixed, "-m", os.path.join(DATA, "ch2bet.nii.gz"),
                   "-p", os.path.join(HERE, "affine.txt"), "-p", os.path.join(HERE, "bspline.txt"),
                   "-out", d, "-threads", str(args.threads)], os.path.join(d, "elastix.out"))
    # the last transform, read with nearest-neighbour labels
    tp = open(os.path.join(d, "TransformParameters.1.txt")).read()
    tp = re.sub(r"\(FinalBSplineInterpolationOrder \d+\)", "(FinalBSplineInterpolationOrder 0)", tp)
    tp = re.sub(r'\(ResultImagePixelType "[a-z]+"\)', '(ResultImagePixelType "short")', tp)
    labels_tp = os.path.join(d, "labels.txt")
    open(labels_tp, "w").write(tp)
    run(["transformix", "-in", os.path.join(DATA, "aal.nii.gz"), "-tp", labels_tp, "-out", d,
         "-threads", str(args.threads)], os.path.join(d, "transformix.out"))
    carried = np.asarray(nibabel.load(os.path.join(d, "result.nii.gz")).dataobj).round().astype(int)
    own = np.asarray(nibabel.load(os.path.join(pair_dir, "subject_atlas.nii.gz")).dataobj).round().astype(int)
    if carried.shape != own.shape:
        sys.exit(f"register_peers: transformix wrote {carried.shape}, the subject's atlas is {own.shape}")
    run(["transformix", "-jac", "all", "-tp", labels_tp, "-out", d, "-threads", str(args.threads)],
        os.path.join(d, "jacobian.out"))
    jac = np.asarray(nibabel.load(os.path.join(d, "spatialJacobian.nii.gz")).dataobj, dtype=float)
    brain = np.asarray(nibabel.load(fixed).dataobj) > 0
    return {
        "method": "elastix",
        "dice_subject": [dice(own, carried, l) for l, _ in HELD_OUT],
        "volume_change": float(np.abs(jac[brain] - 1).mean()),
        "folds": int((jac[brain] <= 0).sum()),
        "seconds": seconds,
    }


def fmt(row):
    ds = " ".join(f"{x:.3f}" for x in row["dice_subject"])
    ball = " ".join(f"{x:.3f}" for x in row["dice_ball"]) if "dice_ball" in row else "-"
    return (f"{row['method']:>14s} {row.get('tets', '-'):>8} | {ds} | {ball:>23s} | "
            f"{100 * row['volume_change']:6.2f}% {row['folds']:5d} | {row['seconds']:7.1f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--pairs", default="build/bench/vpm_bench_pairs")
    ap.add_argument("--seeds", default="1,2,3,4,5")
    ap.add_argument("--demo-pair", action="store_true", help="also the demo's own pair (seed 0)")
    ap.add_argument("--target-vertices", default="5200")
    ap.add_argument("--configs", help="vpm settings to run, ';'-separated: mesh vertices, then ':' and "
                    "more `vpm_bench_pairs` options (e.g. '5200;45000:--dense-restore-cycles 2'); each is labelled "
                    "'vpm N', or 'vpm N+k' when it has options (k: its place in the list, from 0)")
    ap.add_argument("--max-rotation", type=float, default=10)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--no-elastix", action="store_true")
    ap.add_argument("--out", default="build/bench-register-peers")
    ap.add_argument("--json")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",") if s] + ([0] if args.demo_pair else [])
    configs = []  # (vertices, extra options, tag)
    if args.configs:
        for k, item in enumerate(c for c in args.configs.split(";") if c.strip()):
            v, _, extra = item.partition(":")
            configs.append((int(v), extra.split(), f"+{k}" if extra.strip() else ""))
    else:
        configs = [(int(v), [], "") for v in args.target_vertices.split(",") if v]
    os.makedirs(args.out, exist_ok=True)
    head = (f"{'method':>14s} {'tets':>8} | subject-space Dice CL CR TL TR | ball Dice CL CR TL TR | "
            f"volume folds | seconds")
    pairs = []
    for seed in seeds:
        rows = []
        pair_dir = None
        for v, extra, tag in configs:
            pair_dir, row = vpm_pair(args, seed, v, extra, tag, args.out)
            rows.append(row)
        ideal = dict(rows[-1])
        ideal.update(method="ideal", dice_subject=ideal["ideal_dice_subject"], dice_ball=ideal["ideal_dice_ball"],
                     volume_change=float("nan"), folds=0, seconds=float("nan"))
        if not args.no_elastix:
            rows.append(elastix_pair(args, seed, pair_dir, args.out))
        pairs.append({"seed": seed, "volume_preserving": seed > 0, "rows": rows})
        print(f"pair seed {seed}" + ("" if seed > 0 else " (the demo's own pair)"))
        print(head)
        for r in rows + [ideal]:
            print(fmt(r))
        sys.stdout.flush()
    # medians over the volume-preserving pairs, per method
    medians = {}
    for p in pairs:
        if not p["volume_preserving"]:
            continue
        for r in p["rows"]:
            medians.setdefault(r["method"], []).append(r)
    summary = {}
    print(f"medians over {len([p for p in pairs if p['volume_preserving']])} volume-preserving pairs")
    print(head)
    for method, rows in medians.items():
        m = {"method": method, "pairs": len(rows)}
        for key in ("dice_subject", "dice_ball", "ideal_dice_subject"):
            if key in rows[0]:
                m[key] = [statistics.median(r[key][i] for r in rows) for i in range(len(HELD_OUT))]
        for key in ("volume_change", "seconds", "seconds_register", "tets"):
            if key in rows[0]:
                m[key] = statistics.median(r[key] for r in rows)
        m["folds"] = max(r["folds"] for r in rows)
        summary[method] = m
        print(fmt(m))
    out = {"regions": [n for _, n in HELD_OUT], "max_rotation_deg": args.max_rotation, "threads": args.threads,
           "configs": [{"label": f"vpm {v}{t}", "target_vertices": v, "options": e} for v, e, t in configs],
           "pairs": pairs, "medians": summary}
    path = args.json or os.path.join(args.out, "register_peers.json")
    with open(path + ".tmp", "w") as f:
        json.dump(out, f, indent=1)
    os.replace(path + ".tmp", path)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
