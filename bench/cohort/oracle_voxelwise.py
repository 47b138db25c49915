#!/usr/bin/python3
"""The planted foci found voxel by voxel with a perfect registration: the most a voxel-wise
comparison can get out of a synthetic cohort (scripts/synth_cohort.py), whatever the alignment
(bench/results/cohort_oracle/).

Every subject's PET is read on Colin27's 2 mm grid through the inverse of its known deformation
(sub-X_deformation.json: pull(y) is the template point of native y; the native point of a
template point x solves pull(y) = x, by fixed-point iteration y <- y + x - pull(y)), divided by
its mean in the brain mask, optionally smoothed (Gaussian, FWHM in mm, normalised inside the
mask). Patients get a voxel-wise z against the normals' mean and sample std; a focus is a
26-connected cluster of voxels with z <= -extend (or -threshold without extend) holding at least
min_mm3 of voxels at z <= -threshold; each patient's native PET voxel y reads the detection at
pull(y) (nearest voxel) and is scored as bench/cohort/evaluate.py scores vpm's foci.

Usage: oracle_voxelwise.py --bids DIR [--settings "FWHM,THRESHOLD,MIN_MM3,EXTEND;..."] [--out-json PATH]
"""
import argparse
import json
import os
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import evaluate as ev  # noqa: E402
from oracle import deformation  # noqa: E402

DEFAULT = "0,3,420,0;0,3,340,2.5;4,3,340,2.5;6,3,340,2.5;6,3,340,2;8,3,340,2"


def native_of(d, x, iterations=8):
    y = x.copy()
    for _ in range(iterations):
        y = y + (x - d.pull(y))
    return y


def parse_settings(text):
    """[(fwhm, threshold, min_mm3, extend)] of "FWHM,THRESHOLD,MIN_MM3,EXTEND;..."."""
    return [tuple(float(v) for v in item.split(",")) for item in text.split(";") if item.strip()]


def smoother(mask, fwhm):
    """img -> img smoothed by a Gaussian of FWHM mm (2 mm voxels), normalised inside mask, 0 outside."""
    sig = fwhm / 2.3548 / 2.0  # voxels of 2 mm
    weight = mask.astype(np.float64)

    def smooth(img):
        if sig <= 0:
            return img
        return np.where(mask, ndimage.gaussian_filter(img, sig) / np.maximum(ndimage.gaussian_filter(weight, sig), 1e-9), 0)
    return smooth


def detect(z, ok, thr, min_mm3, ext, voxel_mm3):
    """Detected voxels: 26-connected clusters of ok voxels with z <= -extend (or -thr without extend)
    holding >= min_mm3 of voxels at z <= -thr."""
    comp, n = ndimage.label(ok & (z <= -(ext if ext > 0 else thr)), structure=ev.CONN26)
    core = np.bincount(comp.ravel(), weights=(z <= -thr).ravel().astype(np.float64), minlength=n + 1)
    keep = np.nonzero(core * voxel_mm3 >= min_mm3)[0]
    return np.isin(comp, keep[keep > 0])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bids", required=True)
    ap.add_argument("--settings", default=DEFAULT)
    ap.add_argument("--template-data", default="/usr/share/mricron/templates")
    ap.add_argument("--out-json")
    a = ap.parse_args()
    normals, patients = ev.read_participants(a.bids)
    mask, aff2, _ = ev.template_grid(a.template_data)
    x = ev.world(aff2, mask.shape)[:, mask.ravel()]
    imgs = {}
    for sid in normals + patients:
        d = deformation(os.path.join(a.bids, "derivatives", "truth", f"{sid}_deformation.json"))
        pet, paff = ev.load(os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz"))
        v = ndimage.map_coordinates(pet, ev.to_voxel(paff, native_of(d, x)), order=1, mode="constant", cval=0.0)
        img = np.zeros(mask.shape)
        img[mask] = v / v.mean()
        imgs[sid] = (img, d)
    rows_out = []
    for fwhm, thr, min_mm3, ext in parse_settings(a.settings):
        smooth = smoother(mask, fwhm)
        stack = np.array([smooth(imgs[s][0]) for s in normals])
        mean, std = stack.mean(0), stack.std(0, ddof=1)
        del stack
        ok = mask & (std > 0)
        scores = []
        for sid in patients:
            img, d = imgs[sid]
            img = smooth(img)
            z = np.zeros_like(img)
            z[ok] = (img[ok] - mean[ok]) / std[ok]
            det = detect(z, ok, thr, min_mm3, ext, abs(np.linalg.det(aff2[:3, :3])))
            grid = nib.load(os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz"))  # header only
            shape = grid.shape[:3]
            vox = np.rint(ev.to_voxel(aff2, d.pull(ev.world(grid.affine, shape)))).astype(np.int64)
            inb = np.all((vox >= 0) & (vox < np.array(mask.shape)[:, None]), axis=0)
            native = np.zeros(int(np.prod(shape)), dtype=np.uint8)
            native[inb] = det[tuple(vox[:, inb])]
            truth, _ = ev.load(os.path.join(a.bids, "derivatives", "truth", f"{sid}_foci.nii.gz"))
            scores.append(ev.score(native.reshape(shape), truth))
        s = ev.summarise(scores)
        p = s["pooled"]
        row = {"fwhm_mm": fwhm, "threshold": thr, "min_mm3": min_mm3, "extend": ext, **{k: p[k] for k in
               ("sensitivity", "precision", "dice")}, "foci_found": s["foci_found"], "foci_planted": s["foci_planted"],
               "false_positive_clusters": s["false_positive_clusters"]}
        rows_out.append(row)
        print(f"FWHM {fwhm:g} mm, z <= -{thr:g}, >= {min_mm3:g} mm3, extend {ext:g}: overlap {100 * p['sensitivity']:.1f} %, "
              f"precision {100 * p['precision']:.1f} %, Dice {100 * p['dice']:.1f} %, {s['foci_found']}/{s['foci_planted']} "
              f"found, {s['false_positive_clusters']} false clusters", flush=True)
    if a.out_json:
        with open(a.out_json, "w") as f:
            json.dump({"bids": os.path.abspath(a.bids), "normals": len(normals), "patients": len(patients),
                       "rows": rows_out}, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
