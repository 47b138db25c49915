#!/usr/bin/python3
"""The surface maps' anchor (docs/surfaces.md): stretch energy minimisation (SEM; Yueh, Lin, Wu
and Yau, "A Novel Stretch Energy Minimization Algorithm for Equiareal Parameterizations", J. Sci.
Comput. 78, 2019), written here from the paper's formulas (numpy and scipy; not the authors'
MATLAB code), run on the same surfaces as `vpm map` and scored the same way.

SEM to the disk, as implemented:
  1. the harmonic map (cotangent weights) with the boundary loop on the unit circle at angles
     proportional to its arc length;
  2. the stretch Laplacian L_S(f): edge weights w_ij = sum over the edge's faces t of
     cot(theta_ij(f(t))) / (2 sigma(t)), sigma(t) = |t| / |f(t)| (the inverse map's stretch, the
     input's areas scaled to a total of pi), that is <a, b>_f(t) / (4 |t|) for the two edges a, b
     of f(t) at the opposite corner;
  3. repeat: the boundary f_B = -L_BB^-1 L_BI f_I, centred and put on the unit circle; the
     interior f_I = -L_II^-1 L_IB f_B; L_S recomputed; stop when the stretch energy
     E_S(f) = 1/2 trace(f^T L_S(f) f) rises (the previous map is kept), falls by less than
     --tolerance of itself, or after --iterations.
SEM to the sphere, as implemented: from the conformal sphere map (vpm's own, `vpm map --sphere
conformal --rounds 0`: the conformal map and its Moebius balancing), the stretch Laplacian of the
sphere's chord triangles against the input's areas (scaled to the chords' total); repeat: the
stereographic plane inverted (the other hemisphere becomes the inner one), the points inside
radius 1.3 solved with the others held, the plane scaled to a median radius 1, back to the sphere,
the Laplacian recomputed; the same stopping rule.
The score (as vpm's surface metrics): face area ratios (A_f / sum A) / (A0_f / sum A0) of the
flat triangles, mean |r - 1|, and the faces turned against the majority (flipped).

Usage: peer_sem.py OUT_DIR [--runs 3] [--surfaces colin27-patch-ears,colin27-patch,colin27-22k,...]
                   [--iterations 1000] [--tolerance 1e-6] [--vpm build/vpm]
Surfaces are prepared as bench/surfaces/run.py prepares them (OUT_DIR/NAME.off). Writes
OUT_DIR/peer_sem.json and OUT_DIR/peer_sem.md (and prints the table).
"""
import argparse
import importlib.util
import json
import os
import statistics
import sys
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

HERE = os.path.dirname(os.path.abspath(__file__))
_spec = importlib.util.spec_from_file_location("surfaces_run", os.path.join(HERE, "run.py"))
surfaces_run = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(surfaces_run)


def face_areas(x, f):
    a, b, c = x[f[:, 0]], x[f[:, 1]], x[f[:, 2]]
    if x.shape[1] == 2:
        return 0.5 * ((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def boundary_loop(f):
    """The boundary vertices in loop order (one loop: a disk)."""
    half = {}
    for t in f:
        for k in range(3):
            half[(t[k], t[(k + 1) % 3])] = True
    nxt = {a: b for (a, b) in half if (b, a) not in half}
    start = next(iter(nxt))
    loop, v = [start], nxt[start]
    while v != start:
        loop.append(v)
        v = nxt[v]
    return np.array(loop)


def laplacian(x, f, scale):
    """L with weights <a, b> * scale_t / 4 per face corner (the cotangent Laplacian times
    scale_t / |t|_x ... with scale_t = |t|_x / |t|_ref: the stretch Laplacian)."""
    n = len(x)
    rows, cols, vals = [], [], []
    for k in range(3):
        i, j, o = f[:, (k + 1) % 3], f[:, (k + 2) % 3], f[:, k]
        a, b = x[i] - x[o], x[j] - x[o]
        w = np.einsum("ij,ij->i", a, b) * scale / 4
        rows += [i, j]
        cols += [j, i]
        vals += [w, w]
    rows, cols, vals = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    K = sp.csr_matrix((vals, (rows, cols)), shape=(n, n))
    return (sp.diags(np.asarray(K.sum(axis=1)).ravel()) - K).tocsr()


def sem_disk(v, f, iterations, tolerance):
    n = len(v)
    area0 = face_areas(v, f)
    area0 = area0 * np.pi / area0.sum()
    loop = boundary_loop(f)
    inner = np.setdiff1d(np.arange(n), loop)
    seg = np.linalg.norm(v[np.roll(loop, -1)] - v[loop], axis=1)
    theta = 2 * np.pi * np.concatenate([[0.0], np.cumsum(seg)[:-1]]) / seg.sum()
    uv = np.zeros((n, 2))
    uv[loop] = np.column_stack([np.cos(theta), np.sin(theta)])
    # harmonic: cotangent weights of the input, <a, b> / (4 |t|) = cot / 2
    L = laplacian(v, f, 1.0 / face_areas(v, f))
    uv[inner] = spla.spsolve(L[inner][:, inner].tocsc(), -L[inner][:, loop] @ uv[loop])

    def stretch_laplacian(uv):
        x = np.column_stack([uv, np.zeros(n)])
        return laplacian(x, f, 1.0 / area0)

    def energy(uv, L):
        return 0.5 * float(np.sum(uv * (L @ uv)))

    L = stretch_laplacian(uv)
    e0, done = energy(uv, L), 0
    LBB, LBI = L[loop][:, loop].tocsc(), L[loop][:, inner]
    for it in range(iterations):
        prev = uv.copy()
        b = spla.spsolve(LBB, -LBI @ uv[inner])
        b -= b.mean(axis=0)
        uv[loop] = b / np.linalg.norm(b, axis=1)[:, None]
        uv[inner] = spla.spsolve(L[inner][:, inner].tocsc(), -L[inner][:, loop] @ uv[loop])
        L = stretch_laplacian(uv)
        e = energy(uv, L)
        if not e <= e0:
            uv = prev
            break
        gain, e0, done = (e0 - e) / e0, e, it + 1
        if gain < tolerance:
            break
        LBB, LBI = L[loop][:, loop].tocsc(), L[loop][:, inner]
    return uv, done


def sem_sphere(v, f, start, iterations, tolerance, radius=1.3):
    """SEM on the sphere from the sphere map `start` (n x 3 unit vectors)."""
    area0 = face_areas(v, f)
    x = start.copy()
    area0 = area0 * face_areas(x, f).sum() / area0.sum()

    def plane(x):  # stereographic projection from the north pole
        return x[:, :2] / (1 - x[:, 2:3])

    def sphere(uv):
        r2 = np.sum(uv * uv, axis=1, keepdims=True)
        return np.column_stack([2 * uv, r2 - 1]) / (1 + r2)

    def energy(x, L):
        return 0.5 * float(np.sum(x * (L @ x)))

    L = laplacian(x, f, 1.0 / area0)
    e0, done = energy(x, L), 0
    uv = plane(x)
    for it in range(iterations):
        prev_x, prev_uv = x.copy(), uv.copy()
        uv = uv / np.sum(uv * uv, axis=1, keepdims=True)  # inversion: the other hemisphere inside
        inside = np.linalg.norm(uv, axis=1) < radius
        vi, vo = np.where(inside)[0], np.where(~inside)[0]
        uv[vi] = spla.spsolve(L[vi][:, vi].tocsc(), -L[vi][:, vo] @ uv[vo])
        uv = uv / np.median(np.linalg.norm(uv, axis=1))
        x = sphere(uv)
        L = laplacian(x, f, 1.0 / area0)
        e = energy(x, L)
        if not e <= e0:
            x, uv = prev_x, prev_uv
            break
        gain, e0, done = (e0 - e) / e0, e, it + 1
        if gain < tolerance:
            break
    return x, done


def score(v, f, uv):
    a0, a = face_areas(v, f), face_areas(uv, f)
    if uv.shape[1] == 3:  # chord triangles: flipped when facing the centre
        p, q, r = uv[f[:, 0]], uv[f[:, 1]], uv[f[:, 2]]
        a = a * np.sign(np.einsum("ij,ij->i", p, np.cross(q, r)))
    majority = 1.0 if (a > 0).sum() >= (a < 0).sum() else -1.0
    a = a * majority
    r = (a / a.sum()) / (a0 / a0.sum())
    return {"face": float(np.mean(np.abs(r - 1))), "flipped": int((a <= 0).sum()),
            "face_p99_log": float(np.percentile(np.abs(np.log(np.clip(r, 1e-300, None))), 99))}


def read(path):
    v, f = surfaces_run.read_off(path)
    return np.array(v, dtype=float), np.array(f, dtype=np.int64)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--surfaces", default="colin27-patch-ears,colin27-patch")
    ap.add_argument("--iterations", type=int, default=1000)
    ap.add_argument("--tolerance", type=float, default=1e-6)
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for name in a.surfaces.split(","):
        path = surfaces_run.prepare(os.path.abspath(a.vpm), a.out, name, a.timeout)
        v, f = read(path)
        closed = name not in surfaces_run.PATCHES
        secs = []
        for _ in range(a.runs):
            t0 = time.perf_counter()
            if closed:
                start = os.path.join(a.out, name + "_conformal.off")
                rc, _, last = surfaces_run.run([os.path.abspath(a.vpm), "map", path, "--sphere", "conformal", "--rounds",
                                               "0", "-o", start, "--quiet", "--allow-partial"], a.timeout)
                if rc != 0:
                    sys.exit(f"peer_sem.py: the conformal start of {name}: exit {rc}: {last}")
                uv, its = sem_sphere(v, f, read(start)[0], a.iterations, a.tolerance)
            else:
                uv, its = sem_disk(v, f, a.iterations, a.tolerance)
            secs.append(time.perf_counter() - t0)
        row = {"surface": name, "vertices": len(v), "faces": len(f), "iterations": its,
               "seconds": statistics.median(secs), "seconds_all": [round(s, 2) for s in secs]}
        row.update(score(v, f, uv))
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    json.dump({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "runs": a.runs, "rows": rows},
              open(os.path.join(a.out, "peer_sem.json"), "w"), indent=2)
    lines = [f"| surface | vertices / faces | SEM iterations | face area \\|r-1\\| | face p99 \\|log r\\| | flipped "
             f"| s (median of {a.runs}) |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['surface']} | {r['vertices']:,} / {r['faces']:,} | {r['iterations']} | {100 * r['face']:.2f} % "
                     f"| {r['face_p99_log']:.2f} | {r['flipped']} | {r['seconds']:.2f} |")
    md = "\n".join(lines)
    open(os.path.join(a.out, "peer_sem.md"), "w").write(md + "\n")
    print(md)


if __name__ == "__main__":
    main()
