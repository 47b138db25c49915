#!/usr/bin/python3
"""Each focus's family-wise p-value (vpm compare's p_family, from the normals left out by vpm
calibrate) against the planted truth, over held-out cohorts (bench/cohort/heldout.py): does the
p-value tell a planted focus from a false one?

For every cohort of the spec scored by `heldout.py score` with the variant VARIANT (a calibrated
one, so that its foci tables carry p_family), every patient's OUT_foci.tsv is read beside its
OUT_foci.nii.gz (focus ids on the native PET grid): a focus is true when one of its voxels lies in
a planted focus (derivatives/truth/sub-X_foci.nii.gz > 0), false otherwise (the foci-free
patients' foci all are). Written: per role (development, report) the true and false foci by
p_family (each value, as p_family takes (1 + k) / (1 + n)), and how many of the planted foci of
at least 1.5 ml (native PET voxels of the truth mask) with a loss of at least 20 % were found
(one detected voxel in them).

Usage: focus_pvalues.py --out DIR --variant NAME [--spec heldout.json] [--json PATH] [--md PATH]
Exit 2 (one line on stderr) on a missing or malformed input.
"""
import argparse
import csv
import json
import os
import sys
from collections import Counter

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import evaluate  # noqa: E402
import heldout  # noqa: E402


def load_patient(cohort_dir, variant, sid):
    """(detected focus ids, truth ids, truth affine) of one patient, on its native PET grid."""
    base = os.path.join(cohort_dir, "variants", variant, "compare", f"{sid}_pet_foci")
    det, _ = evaluate.load(base + ".nii.gz")
    truth, aff = evaluate.load(os.path.join(cohort_dir, "bids", "derivatives", "truth", f"{sid}_foci.nii.gz"))
    if det.shape != truth.shape:
        evaluate.fail(base + ".nii.gz", f"grid {det.shape} is not the truth's {truth.shape}")
    return det, truth, aff


def patient_foci(cohort_dir, variant, sid, det, truth):
    """[(focus id, p_family or None, true?, volume_mm3, region)] of one patient."""
    base = os.path.join(cohort_dir, "variants", variant, "compare", f"{sid}_pet_foci")
    out = []
    try:
        with open(base + ".tsv", newline="") as f:
            for row in csv.DictReader(f, delimiter="\t"):
                fid = int(row["focus"])
                p = None if row["p_family"] == "NA" else float(row["p_family"])
                mask = np.rint(det) == fid
                true = bool(np.any(truth[mask] > 0))
                out.append((fid, p, true, float(row["volume_mm3"]), row.get("region", "")))
    except (OSError, KeyError, ValueError) as e:
        evaluate.fail(base + ".tsv", f"not a foci table with p_family ({e})")
    return out


def large_foci(cohort_dir, sid, det, truth, aff):
    """Planted foci of >= 1.5 ml (native PET voxels) with >= 20 % loss: [(id, ml, loss, found)]."""
    voxel_ml = abs(np.linalg.det(aff[:3, :3])) / 1000.0
    losses = {}
    with open(os.path.join(cohort_dir, "bids", "derivatives", "truth", "foci.tsv"), newline="") as f:
        for row in csv.DictReader(f, delimiter="\t"):
            if row["participant_id"] == sid:
                losses[int(row["focus"])] = float(row["reduction"])
    out = []
    for fid in np.unique(truth[truth > 0]).astype(int):
        inside = np.rint(truth) == fid
        ml = float(inside.sum()) * voxel_ml
        loss = losses.get(int(fid), float("nan"))
        if ml >= 1.5 and loss >= 0.2:
            out.append((int(fid), round(ml, 2), loss, bool(np.any(det[inside] > 0))))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True, help="heldout.py's --out")
    ap.add_argument("--variant", required=True)
    ap.add_argument("--spec", default=os.path.join(HERE, "heldout.json"))
    ap.add_argument("--json", default="")
    ap.add_argument("--md", default="")
    a = ap.parse_args()
    res = {"variant": a.variant, "cohorts": {}}
    for c in heldout.load_spec(a.spec):
        d = os.path.join(a.out, c["name"])
        _, patients = evaluate.read_participants(os.path.join(d, "bids"))
        grids = {sid: load_patient(d, a.variant, sid) for sid in patients}
        foci = {sid: patient_foci(d, a.variant, sid, *grids[sid][:2]) for sid in patients}
        res["cohorts"][c["name"]] = {
            "role": c["role"], "normals": c["normals"],
            "foci": {sid: [{"focus": f, "p_family": p, "true": t, "volume_mm3": v, "region": r} for f, p, t, v, r in fs]
                     for sid, fs in foci.items()},
            "large_foci": {sid: large_foci(d, sid, *grids[sid]) for sid in patients}}
    lines = [f"Each focus's p_family by truth, variant {a.variant} (a focus is true when it touches a planted one)", ""]
    for role in ("development", "report"):
        names = [n for n, c in res["cohorts"].items() if c["role"] == role]
        true, false = Counter(), Counter()
        for n in names:
            for fs in res["cohorts"][n]["foci"].values():
                for f in fs:
                    key = "NA" if f["p_family"] is None else f"{f['p_family']:.3f}"
                    (true if f["true"] else false)[key] += 1
        keys = sorted(set(true) | set(false), key=lambda k: (k == "NA", float(k) if k != "NA" else 0))
        lines += [f"### {role} cohorts ({', '.join(names)})", "", "| p_family | true foci | false foci |", "|---|---|---|"]
        lines += [f"| {k} | {true[k]} | {false[k]} |" for k in keys]
        large = [f for n in names for fs in res["cohorts"][n]["large_foci"].values() for f in fs]
        lines += ["", f"planted foci of >= 1.5 ml with >= 20 % loss found: {sum(f[3] for f in large)} of {len(large)}", ""]
    text = "\n".join(lines) + "\n"
    if a.json:
        with open(a.json, "w") as f:
            json.dump(res, f, indent=1)
    if a.md:
        with open(a.md, "w") as f:
            f.write(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
