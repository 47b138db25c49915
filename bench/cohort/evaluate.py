#!/usr/bin/python3
"""Scores hypometabolic-foci detection on a synthetic cohort (scripts/synth_cohort.py) against the
planted truth, for vpm and for a baseline "individual image analysis".

1. vpm: RESULTS/compare/sub-X_pet_foci.nii.gz (cluster id > 0, on the patient's PET grid) against
   derivatives/truth/sub-X_foci.nii.gz (focus id 1..K), in native PET voxels.
2. Baseline: each subject's PET is aligned to Colin27 by a 12-parameter affine, the least-squares
   fit mapping its AAL region centroids (sub-X_dseg.nii.gz, world mm) onto Colin27's (aal.nii.gz),
   i.e. the same information vpm's registration uses. PETs are resampled (linear) onto a 2 mm
   template grid, divided by their mean inside the template brain mask (ch2bet > 0 at 2 mm),
   patients get a voxel-wise z against the normals' mean and sample std (ddof=1); z <= -threshold
   in 26-connected clusters of >= --min-cluster-mm3 is detected, pulled back to the patient's PET
   grid through the affine (nearest neighbour), written to RESULTS/baseline/sub-X_foci.nii.gz and
   scored as in 1.

The benchmark's summary (bench/cohort/summary.py) shows by default, as the individual analysis,
the stronger peer bench/cohort/voxelwise_elastix.py (elastix, scored by this file's score and
summarise); the affine baseline stays here for older results (summary.py --individual affine).

Metrics (D = detected voxels, T = planted voxels, native PET grid):
  sensitivity = |D & T| / |T|, precision = |D & T| / |D|, Dice = 2|D & T| / (|D| + |T|),
  Jaccard = |D & T| / |D | T|. "Volume overlap" (Hu et al., TVCG 2014: 94.2 % foci overlap for
  vpm vs 82.2 % for individual analysis) is taken to be the sensitivity: the fraction of the
  planted foci volume covered by detected foci. A focus is found when >= 1 detected voxel lies
  in it; a false-positive cluster is a 26-connected component of D with no truth voxel, a false
  focus one of the method's own foci (a cluster id of its detection image: vpm's focus ids, the
  voxel-wise analyses' clusters) with no truth voxel. A focus that a native image shows in
  pieces (an element cluster across a sulcus, a template cluster pulled back) is one focus, true
  when any piece touches a planted one: each piece that does not is a false-positive cluster.
  Pooled figures sum the voxel counts over patients; means average the per-patient ratios.

Patients planted with no focus (synth_cohort.py --foci-free: an all-zero truth mask) are scored
like the others: every cluster detected there is a false-positive cluster, and its voxels count
in the pooled precision, Dice and Jaccard (the pooled sensitivity is unchanged: they add no truth
voxels); their own ratios with |T| = 0 are null (n/a), or 0 where something was detected. Each
method's summary adds foci_free_patients (how many) and false_clusters_in_foci_free (the
false-positive clusters in them, also counted in false_positive_clusters), and the pooled table
shows them in a column when the cohort has such patients.

Usage: evaluate.py --bids DIR --results DIR [--threshold 3] [--min-cluster-mm3 420]
                   [--out-json PATH] [--out-md PATH] [--template-data DIR]
Exit 2 (one line on stderr) on a missing or malformed input.
"""
import argparse
import csv
import json
import os
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage

CONN26 = np.ones((3, 3, 3), dtype=bool)
RATIOS = ("sensitivity", "precision", "dice", "jaccard", "volume_overlap")


def fail(path, problem):
    print(f"evaluate.py: {path}: {problem}", file=sys.stderr)
    sys.exit(2)


def need(path):
    if not os.path.isfile(path):
        fail(path, "not found")
    return path


def load(path, dtype=np.float64):
    """(3-D data, affine) of a NIfTI; exit 2 if missing, unreadable or not 3-D."""
    try:
        img = nib.load(need(path))
        data = np.asarray(img.dataobj, dtype=dtype)
    except Exception as e:  # nibabel's errors for truncated / non-NIfTI files vary
        fail(path, f"unreadable ({e})")
    if data.ndim > 3 and all(n == 1 for n in data.shape[3:]):
        data = data.reshape(data.shape[:3])
    if data.ndim != 3:
        fail(path, f"not a 3-D image (shape {data.shape})")
    return data, img.affine


def read_participants(bids):
    path = need(os.path.join(bids, "participants.tsv"))
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f, delimiter="\t"))
    for col in ("participant_id", "group"):
        if not rows or col not in rows[0]:
            fail(path, f"no '{col}' column" if rows else "no participants")
    normals = [r["participant_id"].strip() for r in rows if (r["group"] or "").strip() == "normal"]
    patients = [r["participant_id"].strip() for r in rows if (r["group"] or "").strip() == "patient"]
    if len(normals) < 2 or not patients:
        fail(path, f"needs >= 2 normals and >= 1 patient (has {len(normals)} and {len(patients)})")
    return normals, patients


def world(affine, shape):
    """World mm (3, N) of every voxel centre of a grid, C order."""
    idx = np.indices(shape, dtype=np.float64).reshape(3, -1)
    return affine[:3, :3] @ idx + affine[:3, 3:4]


def to_voxel(affine, points):
    inv = np.linalg.inv(affine)
    return inv[:3, :3] @ points + inv[:3, 3:4]


def centroids(labels, affine):
    """{label: world-mm centroid} of every nonzero label."""
    idx = np.nonzero(labels)
    lab = labels[idx].astype(np.int64)
    n = np.bincount(lab)
    pts = affine[:3, :3] @ np.array(idx, dtype=np.float64) + affine[:3, 3:4]
    sums = [np.bincount(lab, weights=p, minlength=len(n)) for p in pts]
    return {k: np.array([s[k] for s in sums]) / n[k] for k in np.nonzero(n)[0]}


def fit_affine(src, dst, path):
    """4x4 least-squares affine mapping the subject's centroids `src` onto the template's `dst`."""
    common = sorted(set(src) & set(dst))
    if len(common) < 4:
        fail(path, f"only {len(common)} AAL labels in common with the template (need >= 4)")
    a = np.array([[*src[k], 1.0] for k in common])
    b = np.array([dst[k] for k in common])
    m = np.linalg.lstsq(a, b, rcond=None)[0]  # (4, 3): [x 1] @ m = y
    out = np.eye(4)
    out[:3, :] = m.T
    return out


def template_grid(data_dir):
    """Colin27 at 2 mm: (brain mask, affine, AAL centroids)."""
    t1, aff = load(os.path.join(data_dir, "ch2bet.nii.gz"))
    aal, aal_aff = load(os.path.join(data_dir, "aal.nii.gz"), np.int64)
    shape = tuple(int(np.ceil(s / 2)) for s in t1.shape)
    aff2 = aff.copy()
    aff2[:3, :3] = aff[:3, :3] * 2
    aff2[:3, 3] = aff[:3, 3] + aff[:3, :3] @ np.full(3, 0.5)  # 2 mm voxels cover the 1 mm grid
    frac = ndimage.map_coordinates((t1 > 0).astype(np.float64), to_voxel(aff, world(aff2, shape)),
                                   order=1, mode="constant", cval=0.0)  # = mean of the 8 voxels
    return frac.reshape(shape) >= 0.5, aff2, centroids(aal, aal_aff)


def to_template(bids, sid, tmpl):
    """Subject's PET on the template grid, proportionally normalised; plus its affine and coverage."""
    mask, aff2, tcent = tmpl
    dseg_path = os.path.join(bids, sid, "anat", f"{sid}_dseg.nii.gz")
    labels, laff = load(dseg_path, np.int64)
    a = fit_affine(centroids(labels, laff), tcent, dseg_path)
    pet, paff = load(os.path.join(bids, sid, "pet", f"{sid}_pet.nii.gz"))
    pts = np.linalg.inv(a) @ np.vstack([world(aff2, mask.shape), np.ones((1, mask.size))])
    vox = to_voxel(paff, pts[:3])
    inside = np.all((vox >= 0) & (vox <= np.array(pet.shape)[:, None] - 1), axis=0).reshape(mask.shape)
    img = ndimage.map_coordinates(pet, vox, order=1, mode="constant", cval=0.0).reshape(mask.shape)
    return img / img[mask & inside].mean(), a, inside


def save_atomic(path, data, affine):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    img = nib.Nifti1Image(data, affine)
    img.set_qform(affine, code=1)
    img.set_sform(affine, code=1)
    tmp = os.path.join(os.path.dirname(path), "." + os.path.basename(path) + ".part.nii.gz")
    nib.save(img, tmp)
    os.replace(tmp, path)


def ratio(num, den):
    return float(num) / den if den else None


def score(detected, truth):
    """Overlap metrics of detection (>0) vs the planted focus ids, native voxels."""
    d, t = detected > 0, truth > 0
    inter, nd, nt = int((d & t).sum()), int(d.sum()), int(t.sum())
    union = int((d | t).sum())
    per_focus = []
    for k in np.unique(truth[t]).astype(int):
        f = truth == k
        n, hit = int(f.sum()), int((f & d).sum())
        per_focus.append({"focus": int(k), "voxels": n, "detected_voxels": hit,
                          "fraction_covered": hit / n, "found": hit > 0})
    comp, ncomp = ndimage.label(d, structure=CONN26)
    with_truth = np.unique(comp[d & t])
    ids = np.unique(detected[d])
    return {"sensitivity": ratio(inter, nt), "precision": ratio(inter, nd),
            "dice": ratio(2 * inter, nd + nt), "jaccard": ratio(inter, union),
            "volume_overlap": ratio(inter, nt),
            "foci_found": sum(p["found"] for p in per_focus), "foci_planted": len(per_focus),
            "false_positive_clusters": int(ncomp - len(with_truth)),
            "false_foci": int(len(ids) - len(np.unique(detected[d & t]))),
            "counts": {"intersection": inter, "detected": nd, "truth": nt, "union": union},
            "per_focus": per_focus}


def summarise(scores):
    c = {k: sum(s["counts"][k] for s in scores) for k in ("intersection", "detected", "truth", "union")}
    pooled = {"sensitivity": ratio(c["intersection"], c["truth"]),
              "precision": ratio(c["intersection"], c["detected"]),
              "dice": ratio(2 * c["intersection"], c["detected"] + c["truth"]),
              "jaccard": ratio(c["intersection"], c["union"]), "counts": c}
    pooled["volume_overlap"] = pooled["sensitivity"]
    means = {}
    for k in RATIOS:
        vals = [s[k] for s in scores if s[k] is not None]
        means[k] = float(np.mean(vals)) if vals else None
    totals = {k: sum(s[k] for s in scores) for k in ("foci_found", "foci_planted", "false_positive_clusters", "false_foci")}
    free = [s for s in scores if s["foci_planted"] == 0]  # planted with nothing: an empty truth mask
    return {"mean_over_patients": means, "pooled": pooled, **totals, "foci_free_patients": len(free),
            "false_clusters_in_foci_free": sum(s["false_positive_clusters"] for s in free)}


def foci_free(summary, scores):
    """(foci-free patients, false-positive clusters in them) of a method: from its summary, or
    counted from its per-patient `scores` for a summary written before these keys existed."""
    if "foci_free_patients" in summary:
        return summary["foci_free_patients"], summary["false_clusters_in_foci_free"]
    free = [s for s in scores if s["foci_planted"] == 0]
    return len(free), sum(s["false_positive_clusters"] for s in free)


def baseline(bids, results, normals, patients, tmpl, threshold, min_mm3):
    """Voxel-wise z after affine alignment; returns {patient: native detection}."""
    mask, aff2, _ = tmpl
    stack, valid = [], mask.copy()
    for sid in normals:
        img, _, inside = to_template(bids, sid, tmpl)
        stack.append(img)
        valid &= inside
    stack = np.array(stack)
    mean, std = stack.mean(0), stack.std(0, ddof=1)
    del stack
    min_vox = min_mm3 / abs(np.linalg.det(aff2[:3, :3]))
    out = {}
    for sid in patients:
        img, a, inside = to_template(bids, sid, tmpl)
        ok = valid & inside & (std > 0)
        z = np.zeros_like(img)
        z[ok] = (img[ok] - mean[ok]) / std[ok]
        comp, n = ndimage.label(ok & (z <= -threshold), structure=CONN26)
        sizes = np.bincount(comp.ravel(), minlength=n + 1)
        keep = np.nonzero(sizes >= min_vox)[0]
        keep = keep[keep > 0]
        lut = np.zeros(n + 1, dtype=np.uint16)
        lut[keep] = np.arange(1, len(keep) + 1)
        clusters = lut[comp]
        # native PET voxel y reads the template detection at A y (nearest neighbour)
        grid = nib.load(os.path.join(bids, sid, "pet", f"{sid}_pet.nii.gz"))  # header only
        shape = grid.shape[:3]
        pts = a @ np.vstack([world(grid.affine, shape), np.ones((1, int(np.prod(shape))))])
        vox = np.rint(to_voxel(aff2, pts[:3])).astype(np.int64)
        inb = np.all((vox >= 0) & (vox < np.array(mask.shape)[:, None]), axis=0)
        native = np.zeros(shape, dtype=np.uint16).ravel()
        native[inb] = clusters[tuple(vox[:, inb])]
        native = native.reshape(shape)
        save_atomic(os.path.join(results, "baseline", f"{sid}_foci.nii.gz"), native, grid.affine)
        out[sid] = native
    return out


def pct(x):
    return "n/a" if x is None else f"{100 * x:.1f} %"


NAMES = {"vpm": "vpm (elements)", "baseline": "individual voxel-wise after affine"}


def markdown(report, methods=("vpm", "baseline"), names=NAMES):
    """Pooled and per-patient tables of report["summary"][m] and report["patients"][i][m], m in methods.
    With patients planted with no focus, the pooled table gets a column of the false-positive
    clusters found in them."""
    head = "| {} | volume overlap (sensitivity) | precision | Dice | foci found | false-positive clusters |\n" \
           "|---|---|---|---|---|---|\n"
    free = {m: foci_free(report["summary"][m], [r[m] for r in report["patients"]]) for m in methods}
    nfree = max(n for n, _ in free.values())
    pooled_head = head.format("method")
    if nfree:
        pooled_head = ("| method | volume overlap (sensitivity) | precision | Dice | foci found | false-positive "
                       f"clusters | of them in the {nfree} foci-free patients |\n|---|---|---|---|---|---|---|\n")
    lines = [f"Pooled over {len(report['patients'])} patients"
             + (f" ({nfree} of them planted with no focus)" if nfree else "")
             + f" (voxel counts summed), threshold z <= "
             f"-{report['threshold']}. Volume overlap = fraction of the planted foci volume covered "
             "by detected foci (sensitivity).\n\n", pooled_head]
    for m in methods:
        s = report["summary"][m]
        p = s["pooled"]
        lines.append(f"| {names[m]} | {pct(p['sensitivity'])} | {pct(p['precision'])} | {pct(p['dice'])} | "
                     f"{s['foci_found']}/{s['foci_planted']} | {s['false_positive_clusters']} |"
                     + (f" {free[m][1]} |" if nfree else "") + "\n")
    lines += ["\nPer patient:\n\n", head.format("patient / method")]
    for r in report["patients"]:
        for m in methods:
            s = r[m]
            lines.append(f"| {r['participant_id']} {names[m]} | {pct(s['sensitivity'])} | {pct(s['precision'])} | "
                         f"{pct(s['dice'])} | {s['foci_found']}/{s['foci_planted']} | "
                         f"{s['false_positive_clusters']} |\n")
    return "".join(lines)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bids", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--threshold", type=float, default=3.0)
    ap.add_argument("--min-cluster-mm3", type=float, default=420.0)
    ap.add_argument("--out-json")
    ap.add_argument("--out-md")
    ap.add_argument("--template-data", default="/usr/share/mricron/templates")
    a = ap.parse_args()
    normals, patients = read_participants(a.bids)
    for f in ("ch2bet.nii.gz", "aal.nii.gz"):  # check every input before the slow part
        need(os.path.join(a.template_data, f))
    for sid in normals + patients:
        need(os.path.join(a.bids, sid, "anat", f"{sid}_dseg.nii.gz"))
        need(os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz"))
    vpm = {}
    for sid in patients:
        truth_path = need(os.path.join(a.bids, "derivatives", "truth", f"{sid}_foci.nii.gz"))
        det_path = need(os.path.join(a.results, "compare", f"{sid}_pet_foci.nii.gz"))
        det, daff = load(det_path)
        truth, taff = load(truth_path)
        if det.shape != truth.shape or not np.allclose(daff, taff, atol=1e-3):
            fail(det_path, f"grid {det.shape} does not match the truth's {truth.shape} ({truth_path})")
        vpm[sid] = (det, truth)
    tmpl = template_grid(a.template_data)
    base = baseline(a.bids, a.results, normals, patients, tmpl, a.threshold, a.min_cluster_mm3)
    rows = [{"participant_id": sid, "vpm": score(*vpm[sid]), "baseline": score(base[sid], vpm[sid][1])}
            for sid in patients]
    report = {"definitions": {
        "sensitivity": "|D & T| / |T|, D = detected voxels, T = planted foci voxels (native PET grid)",
        "precision": "|D & T| / |D|", "dice": "2 |D & T| / (|D| + |T|)", "jaccard": "|D & T| / |D | T|",
        "volume_overlap": "= sensitivity: fraction of the planted foci volume covered by detected foci "
                          "(our reading of Hu et al., TVCG 2014)",
        "foci_found": "planted foci with >= 1 detected voxel",
        "false_positive_clusters": "26-connected components of D with no truth voxel",
        "false_foci": "the method's own foci (the cluster ids of its detection image) with no truth voxel",
        "foci_free_patients": "patients planted with no focus (an all-zero truth mask)",
        "false_clusters_in_foci_free": "false_positive_clusters summed over the foci-free patients "
                                       "(every cluster detected in them)",
        "pooled": "ratios of voxel counts summed over patients",
        "baseline": "AAL-centroid least-squares affine to Colin27, 2 mm template grid, proportional "
                    "scaling, voxel-wise z vs normals (ddof=1), clusters >= min_cluster_mm3, "
                    "pulled back nearest-neighbour"},
        "threshold": a.threshold, "min_cluster_mm3": a.min_cluster_mm3,
        "normals": normals, "patients": rows,
        "summary": {m: summarise([r[m] for r in rows]) for m in ("vpm", "baseline")}}
    md = markdown(report)
    for path, text in ((a.out_json, json.dumps(report, indent=1) + "\n"), (a.out_md, md)):
        if path:
            os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
            with open(path, "w") as f:
                f.write(text)
    print(md, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
