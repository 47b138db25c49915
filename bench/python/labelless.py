#!/usr/bin/python3
"""What registering a subject without atlas labels costs (issue 36; bench/results/cohort_labelless/).

Subjects from scripts/synth_cohort.py (Colin27 through known smooth deformations, their AAL
labels known) are registered to Colin27 twice, on the same ball map:
  * labelled, as the workflow does by default: AAL region centroids (caudate and thalamus held
    out), then 12 dense iterations of force both (region boundaries + T1w);
  * label-less: the labels hidden from vpm (the mesh carries none): landmarks from the affine
    matching the two brains' moments, then 12 dense iterations of the image force alone;
  * and, for scale, the moments' landmarks alone (no dense iterations) and no registration.
Dice of the AAL regions in the common ball is measured as the demo does: ball grid points
carried to each subject's native space through its map and labelled from its own atlas image
(nearest voxel). Reported: the four held-out regions and the mean over all regions.

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/labelless.py [--subjects 4]
           [--out bench/results/labelless.json]
"""
import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import time

import nibabel as nib
import numpy as np

import vpm

TEMPLATES = "/usr/share/mricron/templates"
HELD_OUT = {71: "Caudate_L", 72: "Caudate_R", 77: "Thalamus_L", 78: "Thalamus_R"}
HERE = os.path.dirname(os.path.abspath(__file__))


def labels_at(atlas, points):
    """Nearest-voxel labels of a nibabel image at world points (0 outside the grid)."""
    ijk = np.rint(nib.affines.apply_affine(np.linalg.inv(atlas.affine), points)).astype(int)
    data = np.asanyarray(atlas.dataobj)
    ok = np.all((ijk >= 0) & (ijk < data.shape), axis=1)
    out = np.zeros(len(points), dtype=int)
    out[ok] = data[tuple(ijk[ok].T)]
    return out


def dice(a, b, labels):
    return {int(l): float(2 * np.sum((a == l) & (b == l)) / max(np.sum(a == l) + np.sum(b == l), 1)) for l in labels}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--subjects", type=int, default=4)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--grid", type=int, default=64)
    ap.add_argument("--work", default="out/bench-labelless")
    ap.add_argument("--out", default="bench/results/labelless.json")
    a = ap.parse_args()
    bids = os.path.join(a.work, "bids")
    if not os.path.exists(os.path.join(bids, "participants.tsv")):
        subprocess.run(["/usr/bin/python3", os.path.join(HERE, "..", "..", "scripts", "synth_cohort.py"), "--out", bids,
                        "--normals", str(a.subjects), "--patients", "0", "--seed", str(a.seed), "--jobs", "2"], check=True)
    aal = nib.load(f"{TEMPLATES}/aal.nii.gz")
    template, _ = vpm.mesh_image(f"{TEMPLATES}/ch2bet.nii.gz", labels=f"{TEMPLATES}/aal.nii.gz")
    t_ball, _ = vpm.map_to_ball(template, source="colin27")
    g = (np.arange(a.grid) + 0.5) / a.grid * 2 - 1
    pts = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3)
    pts = pts[np.linalg.norm(pts, axis=1) < 1]
    t_labels = labels_at(aal, vpm.to_native(t_ball, pts))
    regions = sorted(set(np.unique(t_labels)) - {0})
    t1_template = f"{TEMPLATES}/ch2bet.nii.gz"
    rows = []
    for s in range(1, a.subjects + 1):
        sid = f"sub-N{s:02d}"
        t1, dseg = f"{bids}/{sid}/anat/{sid}_T1w.nii.gz", f"{bids}/{sid}/anat/{sid}_dseg.nii.gz"
        mesh, _ = vpm.mesh_image(t1, labels=dseg)
        ball, _ = vpm.map_to_ball(mesh, source=sid)
        bare = vpm.Mesh(ball.vertices, ball.tets, point_data={"original_position": ball.point_data["original_position"]})
        own = nib.load(dseg)
        runs = {
            "none": lambda: (ball, None),
            "labels": lambda: vpm.register(ball, template=t_ball, exclude_labels=list(HELD_OUT), dense_iterations=12,
                                           dense_force="both", image=t1, template_image=t1_template),
            "moments_only": lambda: vpm.register(bare, template=t_ball, template_landmarks="moments"),
            "labelless": lambda: vpm.register(bare, template=t_ball, template_landmarks="moments", dense_iterations=12,
                                              dense_force="image", image=t1, template_image=t1_template),
        }
        row = {"subject": sid}
        for name, run in runs.items():
            t = time.perf_counter()
            reg, rep = run()
            seconds = time.perf_counter() - t
            d = dice(t_labels, labels_at(own, vpm.to_native(reg, pts)), regions)
            row[name] = {"held_out": {HELD_OUT[l]: d[l] for l in HELD_OUT}, "mean_all": statistics.mean(d.values()),
                         "seconds": seconds,
                         "tet_mean_abs_dev": None if rep is None else rep.metrics.tet_volume_ratio.mean_abs_dev}
        rows.append(row)
        print(sid, {k: round(v["mean_all"], 3) for k, v in row.items() if k != "subject"},
              {k: {n: round(x, 3) for n, x in v["held_out"].items()} for k, v in row.items() if k != "subject"})
    summary = {}
    for name in ("none", "labels", "moments_only", "labelless"):
        summary[name] = {"mean_all": statistics.median(r[name]["mean_all"] for r in rows),
                         **{n: statistics.median(r[name]["held_out"][n] for r in rows) for n in HELD_OUT.values()},
                         "seconds": statistics.median(r[name]["seconds"] for r in rows)}
    res = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="minutes"),
           "machine": f"{platform.node()}, {os.cpu_count()} cores", "device": vpm.device_name(),
           "subjects": a.subjects, "seed": a.seed, "grid_points": int(len(pts)), "regions": len(regions),
           "template_vertices": template.num_vertices, "median_over_subjects": summary, "per_subject": rows}
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    json.dump(res, open(a.out, "w"), indent=1)
    for name, s in summary.items():
        print(f"{name:13s} mean Dice (all {len(regions)} regions) {s['mean_all']:.3f}; held out "
              + " ".join(f"{s[n]:.3f}" for n in HELD_OUT.values()) + f"; {s['seconds']:.1f} s")
    print("wrote", a.out)


if __name__ == "__main__":
    main()
