#!/usr/bin/python3
"""The individual analysis a lab would run on a synthetic cohort (scripts/synth_cohort.py): each
PET spatially normalised to Colin27 by elastix (affine then B-spline), smoothed, and compared
voxel by voxel with the normals (SPM's usual single-case practice); the foci are scored as
bench/cohort/evaluate.py scores vpm's.

Per subject (normals and patients alike):
1. elastix registers the subject to the template: fixed = Colin27 (ch2bet.nii.gz), moving = the
   subject's T1w, parameter files bench/register_peers/affine.txt then bspline.txt, one thread;
   subjects run --jobs at a time. The transform T maps a template point x (world mm) to the
   subject's point T(x) showing the same anatomy.
2. `transformix -def all` writes T's displacement field u on the template's 2 mm grid (the grid
   and brain mask of evaluate.py's template_grid; the transform's output grid is rewritten to it);
   u is in ITK's LPS space and is turned to RAS world mm: T(x) = x + u(x). The subject's PET is
   read at T(x) (scipy map_coordinates, linear, 0 outside its grid) at every brain-mask voxel x,
   and divided by its mean over the mask voxels the PET covers (proportional scaling).
   The elastix and transformix outputs stay in RESULTS/peer_elastix/work/sub-X/; a rerun skips
   whatever is there already (delete work/ to register anew), so further settings are scored fast.
Then, per setting "FWHM,THRESHOLD,MIN_MM3,EXTEND" (bench/cohort/oracle_voxelwise.py's smoothing
and clustering, imported): Gaussian smoothing of FWHM mm normalised inside the mask; every
patient's voxel-wise z against the normals' mean and sample std (ddof=1) over the mask voxels
every normal and the patient cover; foci = 26-connected clusters of voxels with z <= -EXTEND
(-THRESHOLD without extend) holding >= MIN_MM3 of voxels at z <= -THRESHOLD. Each native PET
voxel y of the patient reads the detection at the nearest template voxel of T^-1(y), found by
the fixed-point iteration x <- x + (y - T(x)) (u interpolated linearly, constant outside the
grid); the native masks (cluster ids) go to RESULTS/peer_elastix/sub-X_foci.nii.gz for the
default setting 8,3,340,0 and sub-X_foci_fwhmF_zT_minM_extE.nii.gz for others, and are scored
against derivatives/truth/sub-X_foci.nii.gz by evaluate.py's score and summarise (patients planted
with no focus, synth_cohort.py --foci-free, included: whatever is found in them is a false positive,
counted in the summary's false_clusters_in_foci_free as well).

RESULTS/peer_elastix/evaluation.json: per setting the summary and per-patient scores; seconds per
subject (elastix + transformix + warping the PET; cached steps keep the seconds of the run that
made them), median and max; quality checks per subject (Pearson correlation of the warped T1w
with Colin27 over the mask, PET coverage of the mask) and per patient (residual |T(x) - y| of the
inversion over the native voxels whose x lies in the mask, mm).

Usage: voxelwise_elastix.py --bids DIR --results DIR [--jobs 2] [--settings "8,3,340,0;..."]
                            [--template-data DIR]
Exit 2 (one line on stderr) on a missing or malformed input or a failed elastix / transformix.
"""
import argparse
import concurrent.futures
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import threading
import time

import nibabel as nib
import numpy as np
from scipy import ndimage

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import evaluate as ev  # noqa: E402
from oracle_voxelwise import detect, parse_settings, smoother  # noqa: E402

PARAMS = [os.path.normpath(os.path.join(HERE, "..", "register_peers", f)) for f in ("affine.txt", "bspline.txt")]
DEFAULT = "8,3,340,0"
LPS = np.array([-1.0, -1.0, 1.0])  # ITK's physical space (LPS) <-> NIfTI world (RAS), per axis
PROCS, LOCK, ABORT = set(), threading.Lock(), threading.Event()


def fail(path, problem):
    if not ABORT.is_set():
        ABORT.set()
        print(f"voxelwise_elastix.py: {path}: {problem}", file=sys.stderr)
    sys.exit(2)


ev.fail = fail  # evaluate.py's loaders report under this script's name


def run(cmd, log, path):
    """Runs cmd (argv list, no shell) with its output in `log`; seconds, or exit 2 naming `path`."""
    t0 = time.monotonic()
    with open(log, "w") as f:
        with LOCK:
            if ABORT.is_set():
                sys.exit(2)
            p = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT)
            PROCS.add(p)
        rc = p.wait()
        with LOCK:
            PROCS.discard(p)
    if rc != 0:
        fail(path, f"{os.path.basename(cmd[0])} exited {rc} (see {log})")
    return time.monotonic() - t0


def write_json(path, obj):
    tmp = os.path.join(os.path.dirname(path), "." + os.path.basename(path) + ".part")
    with open(tmp, "w") as f:
        json.dump(obj, f, indent=1)
    os.replace(tmp, path)


def grid_parameters(work, mask, aff2):
    """TransformParameters.1.txt with its output grid replaced by the 2 mm template grid (origin in
    LPS; the direction stays Colin27's, which the 2 mm grid shares)."""
    tp = open(os.path.join(work, "TransformParameters.1.txt")).read()
    for name, val in (("Size", " ".join(str(n) for n in mask.shape)), ("Index", "0 0 0"),
                      ("Spacing", " ".join(f"{s:.10f}" for s in np.linalg.norm(aff2[:3, :3], axis=0))),
                      ("Origin", " ".join(f"{o:.10f}" for o in LPS * aff2[:3, 3]))):
        tp = re.sub(rf"\({name} [^)]*\)", f"({name} {val})", tp)
    first = os.path.join(work, "TransformParameters.0.txt")
    tp = re.sub(r'\(InitialTransformParametersFileName "[^"]*"\)',
                f'(InitialTransformParametersFileName "{first}")', tp)
    path = os.path.join(work, "grid2mm.txt")
    with open(path, "w") as f:
        f.write(tp)
    return path


def field(work, mask, aff2):
    """T(x) - x (RAS mm) on the 2 mm template grid, shape (3,) + grid."""
    path = os.path.join(work, "deformationField.nii.gz")
    img = nib.load(path)
    u = np.asarray(img.dataobj, dtype=np.float64)
    if u.shape[:3] != mask.shape or u.size != 3 * mask.size or not np.allclose(img.affine, aff2, atol=1e-3):
        fail(path, f"not a vector field on the 2 mm template grid (shape {u.shape})")
    u = u.reshape(mask.shape + (3,)) * LPS
    return np.ascontiguousarray(np.moveaxis(u, 3, 0))


def at(u, aff2, x):
    """u interpolated (linear, constant beyond the grid) at world points x (3, N)."""
    v = ev.to_voxel(aff2, x)
    return np.array([ndimage.map_coordinates(c, v, order=1, mode="nearest") for c in u])


def subject(sid, bids, root, template, tmpl):
    """Registers and warps one subject: (PET on the template grid, coverage, seconds, checks)."""
    mask, aff2, _ = tmpl
    t1 = os.path.join(bids, sid, "anat", f"{sid}_T1w.nii.gz")
    work = os.path.join(root, "work", sid)
    os.makedirs(work, exist_ok=True)
    timing_path = os.path.join(work, "timing.json")
    timing = json.load(open(timing_path)) if os.path.isfile(timing_path) else {}
    if "elastix_s" not in timing or not os.path.isfile(os.path.join(work, "TransformParameters.1.txt")):
        cmd = ["elastix", "-f", template, "-m", t1, "-p", PARAMS[0], "-p", PARAMS[1], "-out", work, "-threads", "1"]
        timing = {"elastix_s": run(cmd, os.path.join(work, "elastix.out"), t1)}
        write_json(timing_path, timing)
    if "transformix_s" not in timing or not os.path.isfile(os.path.join(work, "deformationField.nii.gz")):
        tp = grid_parameters(work, mask, aff2)
        timing["transformix_s"] = run(["transformix", "-def", "all", "-tp", tp, "-out", work, "-threads", "1"],
                                      os.path.join(work, "transformix.out"), t1)
        write_json(timing_path, timing)
    t0 = time.monotonic()
    x = ev.world(aff2, mask.shape)[:, mask.ravel()]
    tx = x + field(work, mask, aff2)[:, mask]
    pet, paff = ev.load(os.path.join(bids, sid, "pet", f"{sid}_pet.nii.gz"))
    vox = ev.to_voxel(paff, tx)
    covered = np.all((vox >= 0) & (vox <= np.array(pet.shape)[:, None] - 1), axis=0)
    if not covered.any():
        fail(os.path.join(bids, sid, "pet", f"{sid}_pet.nii.gz"), "covers none of the template's brain mask")
    v = ndimage.map_coordinates(pet, vox, order=1, mode="constant", cval=0.0)
    img, inside = np.zeros(mask.shape, dtype=np.float32), np.zeros(mask.shape, dtype=bool)
    img[mask] = v / v[covered].mean()
    inside[mask] = covered
    seconds = {**timing, "warp_s": time.monotonic() - t0}
    seconds["total_s"] = seconds["elastix_s"] + seconds["transformix_s"] + seconds["warp_s"]
    # check (not timed): the subject's T1w carried to the template against Colin27 itself
    t1_img, t1_aff = ev.load(t1)
    colin, caff = ev.load(template)
    a = ndimage.map_coordinates(t1_img, ev.to_voxel(t1_aff, tx), order=1, mode="constant", cval=0.0)
    b = ndimage.map_coordinates(colin, ev.to_voxel(caff, x), order=1, mode="constant", cval=0.0)
    checks = {"t1_correlation": float(np.corrcoef(a, b)[0, 1]), "pet_coverage": float(covered.mean())}
    print(f"voxelwise_elastix: {sid} {seconds['total_s']:.0f} s, warped T1w vs Colin27 r = "
          f"{checks['t1_correlation']:.3f}", flush=True)
    return img, inside, seconds, checks


def native_index(sid, bids, root, tmpl, grid, iterations=30):
    """Flat template-grid index of T^-1(y) (nearest voxel, -1 outside) for every native PET voxel y,
    and the inversion's residual |T(x) - y| (median, max) over the voxels whose x is in the mask."""
    mask, aff2, _ = tmpl
    u = field(os.path.join(root, "work", sid), mask, aff2)
    y = ev.world(grid.affine, grid.shape[:3])
    x = y.copy()
    for _ in range(iterations):
        x_new = y - at(u, aff2, x)  # x + (y - T(x))
        step = float(np.abs(x_new - x).max())
        x = x_new
        if step < 1e-3:
            break
    vox = np.rint(ev.to_voxel(aff2, x)).astype(np.int64)
    inb = np.all((vox >= 0) & (vox < np.array(mask.shape)[:, None]), axis=0)
    flat = np.full(y.shape[1], -1, dtype=np.int64)
    flat[inb] = np.ravel_multi_index(tuple(vox[:, inb]), mask.shape)
    brain = flat >= 0
    brain[brain] = mask.ravel()[flat[brain]]
    res = np.linalg.norm(x + at(u, aff2, x) - y, axis=0)[brain]
    return flat, {"inversion_residual_median_mm": float(np.median(res)) if res.size else None,
                  "inversion_residual_max_mm": float(res.max()) if res.size else None}


def key(setting):
    return ",".join(f"{v:g}" for v in setting)


def label(setting):
    fwhm, thr, min_mm3, ext = setting
    return (f"voxel-wise after elastix (FWHM {fwhm:g}, z <= -{thr:g}, >= {min_mm3:g} mm^3"
            + (f", extent z <= -{ext:g}" if ext > 0 else "") + ")")


def suffix(setting):
    fwhm, thr, min_mm3, ext = setting
    return "" if key(setting) == DEFAULT else f"_fwhm{fwhm:g}_z{thr:g}_min{min_mm3:g}_ext{ext:g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bids", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--jobs", type=int, default=2, help="subjects registered at once (elastix -threads 1 each)")
    ap.add_argument("--settings", default=DEFAULT, help='"FWHM,THRESHOLD,MIN_MM3,EXTEND;..." (default %(default)s)')
    ap.add_argument("--template-data", default="/usr/share/mricron/templates")
    a = ap.parse_args()
    start = time.monotonic()
    try:
        settings = parse_settings(a.settings)
        if not settings or any(len(s) != 4 for s in settings):
            raise ValueError("needs 4 numbers per setting")
    except ValueError as e:
        fail("--settings", f"'{a.settings}' is not FWHM,THRESHOLD,MIN_MM3,EXTEND;... ({e})")
    for tool in ("elastix", "transformix"):
        if shutil.which(tool) is None:
            fail(tool, "not on PATH")
    normals, patients = ev.read_participants(a.bids)
    for sid in normals + patients:  # ids become paths and elastix arguments
        if not re.fullmatch(r"sub-[A-Za-z0-9]+", sid):
            fail(os.path.join(a.bids, "participants.tsv"), f"participant_id '{sid}' is not sub-<alphanumeric label>")
    template = ev.need(os.path.join(a.template_data, "ch2bet.nii.gz"))
    ev.need(os.path.join(a.template_data, "aal.nii.gz"))
    for p in PARAMS:
        ev.need(p)
    for sid in normals + patients:  # check every input before the slow part
        ev.need(os.path.join(a.bids, sid, "anat", f"{sid}_T1w.nii.gz"))
        ev.need(os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz"))
    truths = {}
    for sid in patients:
        truth, taff = ev.load(os.path.join(a.bids, "derivatives", "truth", f"{sid}_foci.nii.gz"))
        pet_path = os.path.join(a.bids, sid, "pet", f"{sid}_pet.nii.gz")
        grid = nib.load(pet_path)  # header only
        if grid.shape[:3] != truth.shape or not np.allclose(grid.affine, taff, atol=1e-3):
            fail(pet_path, f"grid {grid.shape[:3]} does not match the truth's {truth.shape}")
        truths[sid] = (truth, grid)
    root = os.path.abspath(os.path.join(a.results, "peer_elastix"))
    os.makedirs(os.path.join(root, "work"), exist_ok=True)
    tmpl = ev.template_grid(a.template_data)
    mask, aff2, _ = tmpl

    warped = {}
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs))
    futures = {pool.submit(subject, sid, a.bids, root, os.path.abspath(template), tmpl): sid
               for sid in normals + patients}
    try:
        for fut in concurrent.futures.as_completed(futures):
            warped[futures[fut]] = fut.result()
    except BaseException:
        ABORT.set()
        pool.shutdown(wait=False, cancel_futures=True)
        with LOCK:
            for p in PROCS:  # only the elastix / transformix this script started
                p.terminate()
        raise
    pool.shutdown()

    valid = mask.copy()
    for sid in normals:
        valid &= warped[sid][1]
    checks = {sid: warped[sid][3] for sid in normals + patients}
    index = {}
    for sid in patients:
        index[sid], inv = native_index(sid, a.bids, root, tmpl, truths[sid][1])
        checks[sid].update(inv)
    voxel_mm3 = abs(np.linalg.det(aff2[:3, :3]))
    out_settings = []
    for setting in settings:
        fwhm, thr, min_mm3, ext = setting
        smooth = smoother(mask, fwhm)
        stack = np.array([smooth(warped[s][0].astype(np.float64)) for s in normals])
        mean, std = stack.mean(0), stack.std(0, ddof=1)
        del stack
        rows = []
        for sid in patients:
            img = smooth(warped[sid][0].astype(np.float64))
            ok = valid & warped[sid][1] & (std > 0)
            z = np.zeros_like(img)
            z[ok] = (img[ok] - mean[ok]) / std[ok]
            clusters, _ = ndimage.label(detect(z, ok, thr, min_mm3, ext, voxel_mm3), structure=ev.CONN26)
            truth, grid = truths[sid]
            flat = index[sid]
            native = np.zeros(flat.shape, dtype=np.uint16)
            native[flat >= 0] = clusters.ravel()[flat[flat >= 0]]
            native = native.reshape(truth.shape)
            ev.save_atomic(os.path.join(root, f"{sid}_foci{suffix(setting)}.nii.gz"), native, grid.affine)
            rows.append({"participant_id": sid, **ev.score(native, truth)})
        s = ev.summarise(rows)
        p = s["pooled"]
        print(f"{label(setting)}: overlap {ev.pct(p['sensitivity'])}, precision {ev.pct(p['precision'])}, "
              f"Dice {ev.pct(p['dice'])}, {s['foci_found']}/{s['foci_planted']} found, "
              f"{s['false_positive_clusters']} false clusters"
              + (f" ({s['false_clusters_in_foci_free']} in the {s['foci_free_patients']} foci-free patients)"
                 if s["foci_free_patients"] else ""), flush=True)
        out_settings.append({"setting": key(setting), "fwhm_mm": fwhm, "threshold": thr, "min_mm3": min_mm3,
                             "extend": ext, "label": label(setting), "file_suffix": suffix(setting),
                             "summary": s, "patients": rows})
    per = {sid: warped[sid][2] for sid in normals + patients}
    totals = [per[s]["total_s"] for s in per]
    report = {
        "method": "voxel-wise after elastix",
        "description": "elastix affine + B-spline (bench/register_peers/affine.txt, bspline.txt), fixed Colin27 "
                       "ch2bet, moving the subject's T1w; PET read at T(x) on the 2 mm template grid, "
                       "proportional scaling, Gaussian smoothing normalised in the mask, voxel-wise z vs normals "
                       "(ddof=1), clusters pulled back through T^-1 (nearest voxel), scored as evaluate.py",
        "bids": os.path.abspath(a.bids), "template": os.path.abspath(template),
        "default_setting": DEFAULT, "normals": normals, "patients": patients, "settings": out_settings,
        "seconds": {"per_subject": per, "median_s": statistics.median(totals), "max_s": max(totals),
                    "jobs": a.jobs, "wall_s": time.monotonic() - start},
        "checks": checks}
    write_json(os.path.join(root, "evaluation.json"), report)
    corr = [c["t1_correlation"] for c in checks.values()]
    print(f"voxelwise_elastix: {len(per)} subjects, {statistics.median(totals):.0f} s median, {max(totals):.0f} s max "
          f"per subject; warped T1w vs Colin27 r median {statistics.median(corr):.3f}, min {min(corr):.3f}; "
          f"wrote {os.path.join(root, 'evaluation.json')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
