#!/usr/bin/python3
"""The sphere and disk registration benchmark (docs/surfaces.md): a brain surface mapped to the
sphere (a cortical patch to the disk) by `vpm map`, then registered by `vpm register` onto a known
area-preserving deformation of itself, each run several times (medians).

The deformation: three twists, each a rotation about a random axis by an angle that depends on
the height along that axis only (theta(h) = A sin(pi (h + 1) / 2 + phase)). Rotating each
circle of latitude rigidly keeps every area (Archimedes), so the truth is area-preserving and
known at every vertex. Landmarks: L vertices drawn by the seed; targets: their images. Scored:
the landmark error, the face area change against the input sphere (after the flow, after the
restoration), flipped faces, and the distance of every vertex from its true image (radians), the
registration's error where no landmark pins it; for reference, the same distance for the rigid
step alone (what the flow gained).

In the disk (surfaces named *-patch*): a swirl, each circle about the centre turned rigidly by
theta(r) = A sin(pi r + phase) (areas kept, the circle onto itself); landmarks drawn among the
vertices with |x| < 0.9; distances in disk units.

Usage: register.py OUT_DIR [--runs 3] [--surfaces colin27-22k,...] [--landmarks 12,24,48]
                   [--seeds 1,2,3] [--vpm build/vpm] [--timeout 600]
Defaults of the registration (steps 32, width factor 1) were chosen on aal-19k and seeds 1-3;
the report set is Colin27's brain boundary at 22k, 64k, 128k faces, seeds 11-13.
Writes OUT_DIR/register.json and OUT_DIR/register.md.
"""
import argparse
import importlib.util
import json
import os
import statistics
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("surfaces_run", os.path.join(HERE, "run.py"))
_surfaces = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_surfaces)  # bench/surfaces/run.py (which imports bench/shapes/run.py as run)
prepare, run = _surfaces.prepare, _surfaces.run


def twist(x, rng, amplitude):
    """x (n, 3) unit vectors through three random twists (the same rng draws for every call)."""
    for _ in range(3):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        phase = rng.uniform(0, 2 * np.pi)
        h = x @ axis
        theta = amplitude * np.sin(np.pi * (h + 1) / 2 + phase)
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        ax = np.broadcast_to(axis, x.shape)
        x = x * c + np.cross(ax, x) * s + ax * h[:, None] * (1 - c)  # Rodrigues
    return x


def swirl(x, rng, amplitude):
    """x (n, 3) points of the unit disk through a swirl about the centre."""
    phase = rng.uniform(0, 2 * np.pi)
    r = np.linalg.norm(x[:, :2], axis=1)
    theta = 2 * amplitude * np.sin(np.pi * r + phase)
    c, s = np.cos(theta), np.sin(theta)
    return np.column_stack([c * x[:, 0] - s * x[:, 1], s * x[:, 0] + c * x[:, 1], np.zeros(len(x))])


def distance(a, b, disk):
    """Per-row distance: Euclidean in the disk, the angle on the sphere."""
    return np.linalg.norm(a - b, axis=1) if disk else np.arccos(np.clip((a * b).sum(1), -1, 1))


def read_points(path):
    sys.path.insert(0, os.path.join(HERE, "..", "..", "build", "python"))
    import vpm as pyvpm  # noqa: E402
    return pyvpm.read_surface(path)


def one(vpm, out, name, landmarks, seed, runs, timeout, amplitude):
    surface = prepare(vpm, out, name, timeout)
    disk = "patch" in name
    sphere = os.path.join(out, name + ("_disk.gii" if disk else "_sphere.gii"))
    if not os.path.exists(sphere):
        rc, _, last = run([vpm, "map", surface, "-o", sphere, "--quiet"], timeout)
        if rc not in (0, 4):
            sys.exit(f"register.py: vpm map {surface}: exit {rc}: {last}")
    v, _ = read_points(sphere)
    if disk:
        truth = swirl(v, np.random.default_rng(seed), amplitude)
        pool = np.where(np.linalg.norm(v[:, :2], axis=1) < 0.9)[0]
    else:
        v = v / np.linalg.norm(v, axis=1)[:, None]
        truth = twist(v, np.random.default_rng(seed), amplitude)
        pool = np.arange(len(v))
    ids = np.random.default_rng(1000 + seed).choice(pool, landmarks, replace=False)
    src, dst = os.path.join(out, f"{name}_{seed}_{landmarks}_src.csv"), os.path.join(out, f"{name}_{seed}_{landmarks}_dst.csv")
    np.savetxt(src, ids, fmt="%d")
    np.savetxt(dst, truth[ids], delimiter=",", fmt="%.17g")
    row = {"surface": name, "seed": seed, "landmarks": landmarks,
           "set": "development" if name == "aal-19k" or seed < 10 else "report"}
    secs = []
    for k in range(runs):
        report, reg = os.path.join(out, f"{name}_reg{k}.json"), os.path.join(out, f"{name}_reg.gii")
        rc, s, last = run([vpm, "register", sphere, "-o", reg, "--landmarks", src, "--targets", dst, "--report", report,
                           "--quiet"], timeout)
        row.update(exit=rc, message=last)
        if rc != 0:
            return row
        secs.append(s)
    r = json.load(open(report))
    g = r["registration"]
    got, _ = read_points(reg)
    if not disk:
        got = got / np.linalg.norm(got, axis=1)[:, None]
    angle = distance(got, truth, disk)
    row.update(faces=r["input"]["faces"], seconds=statistics.median(secs), seconds_all=[round(x, 2) for x in secs],
               landmark_max_error=r["landmark_max_error"],
               flow_face=g["flow"]["face_area_ratio"]["mean_abs_dev"], face=g["final"]["face_area_ratio"]["mean_abs_dev"],
               flipped=g["final"]["flipped_faces"], restore_rounds=g["restore"]["rounds"],
               truth_mean_rad=float(angle.mean()), truth_p95_rad=float(np.percentile(angle, 95)),
               moved_mean_rad=float(distance(v, truth, disk).mean()))
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--surfaces", default="colin27-22k,colin27-64k,colin27-128k")
    ap.add_argument("--landmarks", default="12,24,48")
    ap.add_argument("--seeds", default="11,12,13")
    ap.add_argument("--amplitude", type=float, default=0.15, help="each twist's largest angle (radians)")
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = [one(os.path.abspath(a.vpm), a.out, name, int(L), int(seed), a.runs, a.timeout, a.amplitude)
            for name in a.surfaces.split(",") for L in a.landmarks.split(",") for seed in a.seeds.split(",")]
    json.dump(rows, open(os.path.join(a.out, "register.json"), "w"), indent=1)
    head = ("| surface | set | seed | landmarks | faces | exit | landmark max error | face area mean abs(r-1) flow / final "
            "| flipped | distance to the truth mean / p95 (rad; the truth moves 0 to it by) | s (median) |")
    lines = [head, "|" + "---|" * 11]
    for r in rows:
        if r.get("exit") != 0:
            lines.append(f"| {r['surface']} | {r['set']} | {r['seed']} | {r['landmarks']} | | {r.get('exit')} | {r.get('message')} | | | | |")
            continue
        lines.append(f"| {r['surface']} | {r['set']} | {r['seed']} | {r['landmarks']} | {r['faces']} | 0 | {r['landmark_max_error']:.1e} "
                     f"| {100 * r['flow_face']:.2f} % / {100 * r['face']:.2f} % | {r['flipped']} "
                     f"| {r['truth_mean_rad']:.4f} / {r['truth_p95_rad']:.4f} ({r['moved_mean_rad']:.4f}) | {r['seconds']:.2f} |")
    open(os.path.join(a.out, "register.md"), "w").write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
