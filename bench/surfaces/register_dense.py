#!/usr/bin/python3
"""The dense sphere registration benchmark (docs/surfaces.md): how close do `vpm register`'s sphere
registrations come to the ideal one on a known area-preserving deformation of a brain surface,
scored by held-out region Dice on the sphere, and what do they cost in area change and time?

For each surface and seed:
  subject   A = OUT/NAME.off (bench/surfaces/run.py), S = its sphere map by `vpm map`
  template  a different triangulation of the same anatomy: the icosphere Y, G of --template-level
            (6: 40,962 vertices) located on S, B = the same barycentric combination of A's
            vertices (the template's 3-D surface); its sphere T = twist(Y) (bench/surfaces/
            register.py's three twists, --amplitude), so the ideal registration of subject
            vertex i is twist(S_i)
  scalars   the cotangent mean curvature of A and of B, each on its own 3-D mesh
  labels    AAL's region at each vertex of A and of B: the nearest labelled voxel within 4 mm
  landmarks K regions (--landmarks) drawn by the seed among those with at least 0.5 % of the
            surface area on both A and B; the subject's landmark is the vertex of A nearest (on
            S) to the region's area-weighted mean of S, its target its true image (with
            --centroid-targets: the region's area-weighted mean of T, which is not a point
            correspondence). Every other such region is held out and scored.
Methods: identity (S itself), landmarks (--landmarks/--targets), curvature (--template,
--overlay, --template-overlay), landmarks+curvature (both), ideal (the truth, no run); `vpm
register` runs --runs times (median seconds; the last run's output is scored).
Scores of a registered sphere X: held-out region Dice on the sphere (200,000 Fibonacci points,
each labelled by the template's region on (T, G) and by the subject's on (X, A's faces): the
label of the corner with the largest barycentric coordinate), their mean, the worst region, the
gap to the ideal's mean (the target: within 0.01), the angular distance of X from the truth
(mean, 95th percentile), the face area mean |r-1| against S and the flipped faces (the report's;
computed here for identity and ideal), the scalar correlation before -> after (dense runs).

Usage: register_dense.py OUT_DIR [--runs 3] [--surfaces colin27-22k,...] [--seeds 11,12,13]
                         [--landmarks 12] [--template-level 6] [--amplitude 0.15]
                         [--vpm build/vpm] [--timeout 600] [--dense-widths W,...]
                         [--methods landmarks,curvature,landmarks+curvature]
Defaults of the dense registration were chosen on aal-19k with seeds 1-3 (the development set);
the report set is Colin27's brain boundary at 22k, 64k, 128k faces, seeds 11-13.
Writes OUT_DIR/register_dense.json and OUT_DIR/register_dense.md (and prints the table).
"""
import argparse
import functools
import importlib.util
import json
import os
import statistics
import sys
import time
from types import SimpleNamespace

import nibabel as nib
import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "build", "python"))
import vpm  # noqa: E402

_spec = importlib.util.spec_from_file_location("surfaces_register", os.path.join(HERE, "register.py"))
_register = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_register)  # bench/surfaces/register.py (which loads bench/surfaces/run.py)
prepare, run, twist = _register.prepare, _register.run, _register.twist

AAL = "/usr/share/mricron/templates/aal.nii"  # Debian package mricron-data: .nii.gz (labels), .nii.txt (names)
POINTS = 200_000  # Fibonacci points of the Dice
MIN_SHARE = 0.005  # a region's least share of the surface area, on A and on B, to be a landmark or scored
REACH_MM = 4  # a vertex's label: the nearest labelled voxel within this distance
METHODS = ["identity", "landmarks", "curvature", "landmarks+curvature", "ideal"]


def unit(x):
    return x / np.linalg.norm(x, axis=-1, keepdims=True)


def icosphere(level):
    """The unit icosphere subdivided `level` times: (vertices, outward-oriented faces)."""
    t = (1 + 5 ** 0.5) / 2
    v = unit(np.array([(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
                       (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)], float))
    f = np.array([(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
                  (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
                  (6, 2, 10), (8, 6, 7), (9, 8, 1)])
    for _ in range(level):
        edges, mid = np.unique(np.sort(f[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1), axis=0, return_inverse=True)
        ab, bc, ca = (len(v) + mid.reshape(-1, 3)).T
        v = np.vstack([v, unit(v[edges[:, 0]] + v[edges[:, 1]])])
        a, b, c = f.T
        f = np.vstack([np.column_stack(t) for t in ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
    return v, f


def fibonacci(n):
    """n nearly uniform points on the unit sphere."""
    k = np.arange(n) + 0.5
    z = 1 - 2 * k / n
    phi = np.pi * (1 + 5 ** 0.5) * k
    r = np.sqrt(1 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def face_areas(v, f):
    return np.linalg.norm(np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), axis=1) / 2


def vertex_areas(v, f):
    """A third of the areas of each vertex's faces."""
    return np.bincount(f.ravel(), weights=np.repeat(face_areas(v, f) / 3, 3), minlength=len(v))


def mean_curvature(v, f):
    """Signed mean curvature per vertex (positive where convex): the cotangent Laplacian of the
    position along the vertex normal, / (2 x the vertex's area)."""
    cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    twice = np.linalg.norm(cross, axis=1)
    lap, normal = np.zeros_like(v), np.zeros_like(v)
    for k in range(3):
        i, j, l = f[:, k], f[:, (k + 1) % 3], f[:, (k + 2) % 3]
        half_cot = ((v[j] - v[i]) * (v[l] - v[i])).sum(1) / twice / 2  # the angle at i, opposite edge j-l
        np.add.at(lap, j, half_cot[:, None] * (v[l] - v[j]))
        np.add.at(lap, l, half_cot[:, None] * (v[j] - v[l]))
        np.add.at(normal, i, cross)
    return -(lap * unit(normal)).sum(1) / (2 * vertex_areas(v, f))


@functools.lru_cache(maxsize=None)
def aal_nearest():
    """(the label of the nearest labelled voxel, its distance in mm) at every voxel, world -> voxel."""
    img = nib.load(AAL + ".gz")
    labels = np.asarray(img.dataobj).astype(np.int64)
    dist, nearest = ndimage.distance_transform_edt(labels == 0, sampling=img.header.get_zooms()[:3], return_indices=True)
    return labels[tuple(nearest)], dist, np.linalg.inv(img.affine)


def aal_labels(points):
    """AAL's region at each world point (mm): the nearest labelled voxel's within REACH_MM, else 0."""
    label, dist, to_voxel = aal_nearest()
    ijk = np.rint(points @ to_voxel[:3, :3].T + to_voxel[:3, 3]).astype(int)
    at = tuple(np.clip(ijk, 0, np.array(label.shape) - 1).T)
    return np.where(dist[at] <= REACH_MM, label[at], 0)


def labels_on_sphere(sphere, faces, labels, points):
    """The label of the corner with the largest barycentric coordinate where each point lies."""
    face, bary = vpm.locate_on_sphere(sphere, faces, points)
    return labels[faces[face, bary.argmax(1)]]


def area_change(x, reference, faces):
    """(face area mean |r-1| of x against reference, flipped faces): `vpm register`'s report metrics."""
    a, a0 = face_areas(x, faces), face_areas(reference, faces)
    flipped = np.einsum("ij,ij->i", x[faces[:, 0]], np.cross(x[faces[:, 1]], x[faces[:, 2]])) <= 0
    return float(np.abs(a / a.sum() / (a0 / a0.sum()) - 1).mean()), int(flipped.sum())


def centroid(sphere, area, mask):
    """The normalised area-weighted mean of the sphere points in mask."""
    return unit(area[mask] @ sphere[mask])


def subject(vpm_cli, out, name, level, timeout):
    """What no seed changes: the subject A, F, S, the template's icosphere Y, G and 3-D surface B,
    both scalars (written as curv files), labels and vertex areas."""
    surface = prepare(vpm_cli, out, name, timeout)
    sphere = os.path.join(out, name + "_sphere.gii")
    if not os.path.exists(sphere):
        rc, _, last = run([vpm_cli, "map", surface, "-o", sphere, "--quiet"], timeout)
        if rc not in (0, 4):
            sys.exit(f"register_dense.py: vpm map {surface}: exit {rc}: {last}")
    A, F = vpm.read_surface(surface)
    S = unit(vpm.read_surface(sphere)[0])
    Y, G = icosphere(level)
    face, bary = vpm.locate_on_sphere(S, F, Y)
    B = np.einsum("kij,ki->kj", A[F[face]], bary)
    s = SimpleNamespace(name=name, A=A, F=F, S=S, sphere=sphere, Y=Y, G=G, B=B, labels_A=aal_labels(A),
                        labels_B=aal_labels(B), area_A=vertex_areas(A, F), area_B=vertex_areas(B, G),
                        curv_A=os.path.join(out, f"{name}_dense.curv"), curv_B=os.path.join(out, f"{name}_dense_template.curv"))
    nib.freesurfer.write_morph_data(s.curv_A, mean_curvature(A, F).astype(np.float32))
    nib.freesurfer.write_morph_data(s.curv_B, mean_curvature(B, G).astype(np.float32))
    return s


def regions(s, seed, count):
    """(landmark regions, held-out regions): the regions with MIN_SHARE of the area on A and B."""
    share = [np.bincount(lab, weights=area) / area.sum() for lab, area in ((s.labels_A, s.area_A), (s.labels_B, s.area_B))]
    n = min(len(x) for x in share)
    big = [r for r in range(1, n) if share[0][r] >= MIN_SHARE and share[1][r] >= MIN_SHARE]
    chosen = sorted(int(r) for r in np.random.default_rng(1000 + seed).choice(big, count, replace=False))
    return chosen, [r for r in big if r not in chosen]


def landmark_files(s, T, truth, chosen, out, seed, centroid_targets):
    """The subject's landmarks (vertex ids: the vertex nearest each region's centroid on S) and
    their targets: the landmarks' true images, or with centroid_targets the region's centroid on
    T (a region centroid is not a point correspondence: the twist does not commute with the mean,
    and the two triangulations label the regions' edges differently)."""
    src, dst = (os.path.join(out, f"{s.name}_dense{seed}_{k}.csv") for k in ("src", "dst"))
    ids = [int(np.argmax(s.S @ centroid(s.S, s.area_A, s.labels_A == r))) for r in chosen]
    np.savetxt(src, ids, fmt="%d")
    targets = [centroid(T, s.area_B, s.labels_B == r) for r in chosen] if centroid_targets else truth[ids]
    np.savetxt(dst, targets, delimiter=",", fmt="%.17g")
    return src, dst


def register(vpm_cli, s, base, args, runs, timeout):
    """`vpm register` on the subject's sphere `runs` times: (the row's fields, the last output or None)."""
    secs, reg = [], base + ".gii"
    for k in range(runs):
        report = f"{base}{k}.json"
        rc, sec, last = run([vpm_cli, "register", s.sphere, "-o", reg, *args, "--report", report, "--quiet"], timeout)
        if rc not in (0, 4):
            return {"exit": rc, "message": last}, None
        secs.append(sec)
    r = json.load(open(report))
    g = r["registration"]
    fields = {"exit": rc, "message": last, "seconds": statistics.median(secs), "seconds_all": [round(x, 2) for x in secs],
              "report_total_s": r["timings_s"]["total"], "landmark_max_error": r["landmark_max_error"],
              "face": g["final"]["face_area_ratio"]["mean_abs_dev"], "flipped": g["final"]["flipped_faces"]}
    if "match" in g:
        fields.update(correlation_before=g["match"]["correlation_before"], correlation_after=g["match"]["correlation_after"])
    return fields, unit(vpm.read_surface(reg)[0])


def score(s, X, truth, points, template_labels, held, names):
    """Held-out region Dice on the sphere and the distance from the truth of the registered sphere X."""
    q = labels_on_sphere(X, s.F, s.labels_A, points)
    dice = {names[r]: 2 * np.sum((template_labels == r) & (q == r)) / (np.sum(template_labels == r) + np.sum(q == r))
            for r in held}
    worst = min(dice, key=dice.get)
    angle = np.arccos(np.clip((X * truth).sum(1), -1, 1))
    return {"dice_mean": float(np.mean(list(dice.values()))), "dice_worst": float(dice[worst]), "dice_worst_region": worst,
            "dice": {k: float(v) for k, v in dice.items()},
            "truth_mean_rad": float(angle.mean()), "truth_p95_rad": float(np.percentile(angle, 95))}


def one_seed(vpm_cli, s, out, seed, a, names):
    """The rows of every method on one surface and seed."""
    T = twist(s.Y, np.random.default_rng(seed), a.amplitude)
    truth = twist(s.S, np.random.default_rng(seed), a.amplitude)
    tpl = os.path.join(out, f"{s.name}_dense{seed}_template.gii")
    vpm.write_surface(tpl, T, s.G)
    chosen, held = regions(s, seed, a.landmarks)
    src, dst = landmark_files(s, T, truth, chosen, out, seed, a.centroid_targets)
    points = fibonacci(POINTS)
    template_labels = labels_on_sphere(T, s.G, s.labels_B, points)
    landmarks = ["--landmarks", src, "--targets", dst]
    dense = ["--template", tpl, "--overlay", s.curv_A, "--template-overlay", s.curv_B]
    if a.dense_widths:
        dense += ["--dense-widths", a.dense_widths]
    args = {"landmarks": landmarks, "curvature": dense, "landmarks+curvature": landmarks + dense}
    rows = []
    for method in [m for m in METHODS if m in a.methods.split(",") or m not in args]:
        row = {"surface": s.name, "set": "development" if s.name == "aal-19k" or seed < 10 else "report", "seed": seed,
               "method": method, "faces": len(s.F), "template_faces": len(s.G), "landmark_regions": [names[r] for r in chosen],
               "held_out_regions": len(held)}
        if method in args:
            fields, X = register(vpm_cli, s, os.path.join(out, f"{s.name}_dense{seed}_{method}"), args[method], a.runs, a.timeout)
            row.update(fields)
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


def table(rows, runs, distance="truth_mean_rad", p95="truth_p95_rad", unit=" (rad)"):
    """The markdown table of the rows; `distance`, `p95` the keys of the distance to the truth."""
    lines = ["| surface | set | seed | method | exit | landmarks / held-out regions | held-out Dice mean / worst (region) "
             f"| gap to the ideal's mean | distance to the truth mean / p95{unit} | face area mean \\|r-1\\| | flipped "
             f"| scalar correlation before -> after | s (median of {runs}) |", "|" + "---|" * 13]
    for r in rows:
        head = (f"| {r['surface']} | {r['set']} | {r['seed']} | {r['method']} | {'-' if r['exit'] is None else r['exit']} "
                f"| {len(r['landmark_regions'])} / {r['held_out_regions']} ")
        if "dice_mean" not in r:
            lines.append(head + f"| {r['message']} |||||||")
            continue
        corr = f"{r['correlation_before']:.3f} -> {r['correlation_after']:.3f}" if "correlation_after" in r else "-"
        secs = f"{r['seconds']:.2f}" if "seconds" in r else "-"
        lines.append(head + f"| {r['dice_mean']:.4f} / {r['dice_worst']:.3f} ({r['dice_worst_region']}) | {r['dice_gap']:.4f} "
                     f"| {r[distance]:.4f} / {r[p95]:.4f} | {100 * r['face']:.2f} % | {r['flipped']} "
                     f"| {corr} | {secs} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--surfaces", default="colin27-22k,colin27-64k,colin27-128k")
    ap.add_argument("--seeds", default="11,12,13")
    ap.add_argument("--landmarks", type=int, default=12, help="landmark regions (the rest are held out)")
    ap.add_argument("--centroid-targets", action="store_true",
                    help="landmark targets: the regions' centroids on the template (default: the landmarks' true images)")
    ap.add_argument("--template-level", type=int, default=6, help="the template icosphere's subdivisions")
    ap.add_argument("--amplitude", type=float, default=0.15, help="each twist's largest angle (radians)")
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    ap.add_argument("--dense-widths", default="", help="passed to vpm register --dense-widths (default: vpm's)")
    ap.add_argument("--methods", default="landmarks,curvature,landmarks+curvature",
                    help="the registrations run (identity and ideal are always scored)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    vpm_cli = os.path.abspath(a.vpm)
    names = vpm.read_label_names(AAL + ".txt")
    rows = []
    for name in a.surfaces.split(","):
        s = subject(vpm_cli, a.out, name, a.template_level, a.timeout)
        for seed in a.seeds.split(","):
            rows += one_seed(vpm_cli, s, a.out, int(seed), a, names)
    json.dump({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "runs": a.runs, "landmarks": a.landmarks,
               "dense_widths": a.dense_widths or "default",
               "template_level": a.template_level, "amplitude": a.amplitude, "points": POINTS, "rows": rows},
              open(os.path.join(a.out, "register_dense.json"), "w"), indent=1)
    md = table(rows, a.runs)
    open(os.path.join(a.out, "register_dense.md"), "w").write(md + "\n")
    print(md)


if __name__ == "__main__":
    main()
