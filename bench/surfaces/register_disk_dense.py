#!/usr/bin/python3
"""The dense disk registration benchmark (docs/surfaces.md): how close do `vpm register`'s disk
registrations come to the ideal one on a known area-preserving deformation of a cortical patch,
scored by held-out region Dice in the disk, and what do they cost in area change and time?

For each surface and seed (bench/surfaces/register_dense.py's design in the disk):
  subject   A = the patch of OUT/SOURCE.off (bench/surfaces/run.py: the faces whose centroid is in
            the top 35 % of its height, the ears removed), D = its disk map by `vpm map`
  template  a different triangulation of the same anatomy: a sunflower of --template-vertices
            points in the disk and a ring on the circle, Delaunay-triangulated (Y, G), located on
            D, B = the same barycentric combination of A's vertices; its disk T = flow(Y), the
            flow of a random stream function psi = (1 - r^2) sum_k a_k sin(w_k . x + phi_k)
            (divergence-free, tangent to the circle: areas kept, boundary sliding), largest speed
            --amplitude, 64 RK4 steps; the ideal registration of subject vertex i is flow(D_i)
  scalars   the cotangent mean curvature of A and of B, each on its own 3-D mesh
  labels    AAL's region at each vertex of A and of B
  landmarks K regions (--landmarks) drawn by the seed among those with 0.5 % of the area on both;
            the subject's landmark is the vertex of D nearest the region's area-weighted mean of
            D, its target its true image; every other such region is held out and scored.
Methods and scores as register_dense.py's, Dice on 200,000 sunflower points of the disk (located
on the disks lifted to the hemisphere by Lambert's equal-area projection), distances in disk units.

Usage: register_disk_dense.py OUT_DIR [--runs 3] [--surfaces colin27-22k,...] [--seeds 11,12,13]
                              [--landmarks 8] [--template-vertices 20000] [--amplitude 0.3]
                              [--vpm build/vpm] [--timeout 600] [--methods ...]
The development set is the patch of aal-19k with seeds 1-3; the report set the patches of
Colin27's brain boundary at 22k, 64k, 128k faces, seeds 11-13. Writes OUT_DIR/register_disk_dense.json
and OUT_DIR/register_disk_dense.md (and prints the table).
"""
import argparse
import importlib.util
import json
import os
import sys
import time
from types import SimpleNamespace

import nibabel as nib
import numpy as np
from scipy.spatial import Delaunay

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("surfaces_register_dense", os.path.join(HERE, "register_dense.py"))
rd = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(rd)  # bench/surfaces/register_dense.py (its scoring, labels, curvature, runs)
vpm = rd.vpm
GOLDEN = np.pi * (3 - 5 ** 0.5)


def sunflower(n, radius=1.0):
    """n nearly uniform points in the disk of `radius`."""
    k = np.arange(n) + 0.5
    r = radius * np.sqrt(k / n)
    return np.column_stack([r * np.cos(GOLDEN * k), r * np.sin(GOLDEN * k), np.zeros(n)])


def disk_template(n):
    """A Delaunay triangulation of the unit disk: n sunflower points inside, a ring on the circle."""
    ring = int(round(2 * np.pi * np.sqrt(n / np.pi)))
    t = 2 * np.pi * np.arange(ring) / ring
    spacing = 2 * np.pi / ring
    Y = np.vstack([sunflower(n, 1 - spacing / 2), np.column_stack([np.cos(t), np.sin(t), np.zeros(ring)])])
    G = Delaunay(Y[:, :2]).simplices.astype(np.int32)
    e1, e2 = Y[G[:, 1]] - Y[G[:, 0]], Y[G[:, 2]] - Y[G[:, 0]]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    G[cw] = G[cw][:, [0, 2, 1]]
    return Y, G


def lift(x):
    """Points of the unit disk on the upper hemisphere (Lambert's equal-area projection)."""
    r2 = np.minimum((x[:, :2] ** 2).sum(1), 1.0)
    s = np.sqrt(2 - r2)
    return np.column_stack([s * x[:, 0], s * x[:, 1], 1 - r2 + 1e-12])


def locate(disk, faces, points):
    return vpm.locate_on_sphere(rd.unit(lift(disk)), faces, lift(points))


def flow(x, seed, amplitude, steps=64):
    """x (n, 3) points of the unit disk through the flow of a random stream function for time 1."""
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(4, 2)) * 2.5
    phi, a = rng.uniform(0, 2 * np.pi, 4), rng.normal(size=4)

    def velocity(p, scale=1.0):
        s = 1 - (p ** 2).sum(1)
        arg = p @ w.T + phi
        f, df = np.sin(arg) @ a, (np.cos(arg) * a) @ w  # sum a_k sin, its gradient
        grad = s[:, None] * df - 2 * p * f[:, None]
        return scale * np.column_stack([grad[:, 1], -grad[:, 0]])

    scale = amplitude / np.linalg.norm(velocity(sunflower(20000)[:, :2]), axis=1).max()
    p = x[:, :2].copy()
    dt = 1.0 / steps
    for _ in range(steps):
        k1 = velocity(p, scale)
        k2 = velocity(p + dt / 2 * k1, scale)
        k3 = velocity(p + dt / 2 * k2, scale)
        k4 = velocity(p + dt * k3, scale)
        p = p + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    r = np.linalg.norm(p, axis=1)
    p[r > 1] /= r[r > 1, None]
    on = np.abs(np.linalg.norm(x[:, :2], axis=1) - 1) < 1e-9
    p[on] /= np.linalg.norm(p[on], axis=1)[:, None]
    return np.column_stack([p, np.zeros(len(p))])


def subject(vpm_cli, out, source, n_template, timeout):
    """What no seed changes: the patch A, F, its disk D, the template's disk mesh Y, G and 3-D
    surface B, both scalars (written as curv files), labels and vertex areas."""
    name = source + "-patch"
    surface = os.path.join(out, name + ".off")
    if not os.path.exists(surface):
        rd.prepare(vpm_cli, out, source, timeout)
        rd._register._surfaces.patch(os.path.join(out, source + ".off"), surface, strip_ears=True)
    disk = os.path.join(out, name + "_disk.gii")
    if not os.path.exists(disk):
        rc, _, last = rd.run([vpm_cli, "map", surface, "-o", disk, "--quiet"], timeout)
        if rc not in (0, 4):
            sys.exit(f"register_disk_dense.py: vpm map {surface}: exit {rc}: {last}")
    A, F = vpm.read_surface(surface)
    D = vpm.read_surface(disk)[0].astype(np.float64)
    D[:, 2] = 0
    Y, G = disk_template(n_template)
    face, bary = locate(D, F, Y)
    B = np.einsum("kij,ki->kj", A[F[face]], bary)
    s = SimpleNamespace(name=name, A=A, F=F, S=D, sphere=disk, Y=Y, G=G, B=B, labels_A=rd.aal_labels(A),
                        labels_B=rd.aal_labels(B), area_A=rd.vertex_areas(A, F), area_B=rd.vertex_areas(B, G),
                        curv_A=os.path.join(out, f"{name}_dense.curv"), curv_B=os.path.join(out, f"{name}_dense_template.curv"))
    nib.freesurfer.write_morph_data(s.curv_A, rd.mean_curvature(A, F).astype(np.float32))
    nib.freesurfer.write_morph_data(s.curv_B, rd.mean_curvature(B, G).astype(np.float32))
    return s


def area_change(x, reference, faces):
    """(face area mean |r-1| of x against reference, flipped faces) in the disk."""
    a, a0 = rd.face_areas(x, faces), rd.face_areas(reference, faces)
    e1, e2 = x[faces[:, 1]] - x[faces[:, 0]], x[faces[:, 2]] - x[faces[:, 0]]
    flipped = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] <= 0
    return float(np.abs(a / a.sum() / (a0 / a0.sum()) - 1).mean()), int(flipped.sum())


def labels_at(disk, faces, labels, points):
    face, bary = locate(disk, faces, points)
    return labels[faces[face, bary.argmax(1)]]


def score(s, X, truth, points, template_labels, held, names):
    q = labels_at(X, s.F, s.labels_A, points)
    dice = {names[r]: 2 * np.sum((template_labels == r) & (q == r)) / (np.sum(template_labels == r) + np.sum(q == r))
            for r in held}
    worst = min(dice, key=dice.get)
    d = np.linalg.norm(X - truth, axis=1)
    return {"dice_mean": float(np.mean(list(dice.values()))), "dice_worst": float(dice[worst]), "dice_worst_region": worst,
            "dice": {k: float(v) for k, v in dice.items()}, "truth_mean": float(d.mean()), "truth_p95": float(np.percentile(d, 95))}


def one_seed(vpm_cli, s, out, seed, a, names):
    T, truth = flow(s.Y, seed, a.amplitude), flow(s.S, seed, a.amplitude)
    tpl = os.path.join(out, f"{s.name}_dense{seed}_template.gii")
    vpm.write_surface(tpl, T, s.G)
    chosen, held = rd.regions(s, seed, a.landmarks)
    src, dst = (os.path.join(out, f"{s.name}_dense{seed}_{k}.csv") for k in ("src", "dst"))
    ids = []
    for r in chosen:
        m = s.labels_A == r
        c = s.area_A[m] @ s.S[m] / s.area_A[m].sum()
        ids.append(int(np.argmin(np.linalg.norm(s.S - c, axis=1))))
    np.savetxt(src, ids, fmt="%d")
    np.savetxt(dst, truth[ids], delimiter=",", fmt="%.17g")
    points = sunflower(rd.POINTS, 1 - 1e-9)
    template_labels = labels_at(T, s.G, s.labels_B, points)
    landmarks = ["--landmarks", src, "--targets", dst]
    dense = ["--template", tpl, "--overlay", s.curv_A, "--template-overlay", s.curv_B]
    args = {"landmarks": landmarks, "curvature": dense, "landmarks+curvature": landmarks + dense}
    rows = []
    for method in [m for m in rd.METHODS if m in a.methods.split(",") or m not in args]:
        row = {"surface": s.name, "set": "development" if seed < 10 else "report", "seed": seed, "method": method,
               "faces": len(s.F), "template_faces": len(s.G), "landmark_regions": [names[r] for r in chosen],
               "held_out_regions": len(held)}
        if method in args:
            fields, X = rd.register(vpm_cli, s, os.path.join(out, f"{s.name}_dense{seed}_{method}"), args[method], a.runs, a.timeout)
            row.update(fields)
            if X is not None:
                X = vpm.read_surface(os.path.join(out, f"{s.name}_dense{seed}_{method}.gii"))[0].astype(np.float64)
        else:
            X = s.S if method == "identity" else truth
            face, flipped = area_change(X, s.S, s.F)
            row.update(exit=None, face=face, flipped=flipped)
        if X is not None:
            row.update(score(s, X, truth, points, template_labels, held, names))
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items() if k != "dice"}), file=sys.stderr, flush=True)
    ideal = rows[-1]["dice_mean"]
    for row in rows:
        if "dice_mean" in row:
            row["dice_gap"] = ideal - row["dice_mean"]
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--surfaces", default="colin27-22k,colin27-64k,colin27-128k", help="the patches' sources")
    ap.add_argument("--seeds", default="11,12,13")
    ap.add_argument("--landmarks", type=int, default=8, help="landmark regions (the rest are held out)")
    ap.add_argument("--template-vertices", type=int, default=20000)
    ap.add_argument("--amplitude", type=float, default=0.3, help="the flow's largest speed (disk units over time 1)")
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    ap.add_argument("--methods", default="landmarks,curvature,landmarks+curvature",
                    help="the registrations run (identity and ideal are always scored)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    vpm_cli = os.path.abspath(a.vpm)
    names = vpm.read_label_names(rd.AAL + ".txt")
    rows = []
    for source in a.surfaces.split(","):
        s = subject(vpm_cli, a.out, source, a.template_vertices, a.timeout)
        for seed in a.seeds.split(","):
            rows += one_seed(vpm_cli, s, a.out, int(seed), a, names)
    json.dump({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "runs": a.runs, "landmarks": a.landmarks,
               "template_vertices": a.template_vertices, "amplitude": a.amplitude, "points": rd.POINTS, "rows": rows},
              open(os.path.join(a.out, "register_disk_dense.json"), "w"), indent=1)
    md = rd.table(rows, a.runs, "truth_mean", "truth_p95", "")
    open(os.path.join(a.out, "register_disk_dense.md"), "w").write(md + "\n")
    print(md)


if __name__ == "__main__":
    main()
