#!/usr/bin/python3
"""Synthesises a cohort with ground truth from the one labelled brain Debian ships (Colin27 and
its AAL atlas, mricron-data): normals and patients as a BIDS dataset, patients with planted
hypometabolic foci whose native-space masks are kept as the truth.

Each subject is Colin27 pulled through its own random, smooth, invertible deformation
(seeded): a rotation of up to --max-rotation degrees, an anisotropic scaling of up to
--max-scaling, and a divergence-free displacement (the curl of Gaussian vector potentials, so
volumes are kept to first order) of a few mm. Its PET-like image is the uptake of Colin27's
tissue classes (grey matter 1, white matter 0.3, CSF 0.05, from the T1 intensity) smoothed to
PET resolution (FWHM --fwhm mm); each patient's --foci-per-patient foci (balls of 8-20 mm
diameter centred in grey matter at least 0.8 radius deep, uptake at PET resolution lowered inside
by a fraction drawn uniformly from --reduction, 15-30 % by default, a soft 2 mm edge) are planted
in Colin27's space. The last --foci-free patients get no focus at all: patients by group, with an
empty truth mask, so that anything found in them is a false positive (bench/cohort/evaluate.py).
A patient without foci draws nothing for them; with the default options a cohort is the same,
bit for bit, as before these two options existed. The result is pulled into the subject's space on a 2 mm
grid, given a smooth multiplicative bias (about 1.5 % per 80 mm), spatially correlated Gaussian
noise (FWHM --noise-fwhm mm, 4 by default; 0: white noise; std --noise of grey-matter uptake) and
a per-subject global scale (0.7-1.3). With --cortical the foci are centred only in the cerebral
cortex (AAL regions other than the caudate, putamen, pallidum, thalamus, hippocampus, amygdala,
cerebellum and vermis): the issue-35 cohort's "cortical foci".
The truth mask of a focus is its ball where the uptake is at least 0.4 (grey matter, mostly).

Every subject has an age (uniform 20-80 years, one decimal) and a sex (F or M, a fair coin) in
participants.tsv, drawn from a stream of their own (seed [S, 7], one age and one sex per subject in
subject order), so that they change nothing else: without --age-effect and --sex-effect they are
labels only and the images are the same, bit for bit, as before these columns existed. With them
the tissue uptake, before the PET smoothing (the foci's stage: the uptake at PET resolution is that
of the scaled tissue), is scaled per subject in the AAL regions (grey matter; names from the
atlas' aal.nii.txt): by 1 - F (age - 50) / 10 in the frontal lobes (Frontal_*, Supp_Motor_Area_*,
Olfactory_*, Rectus_*; not Precentral, Rolandic_Oper or Paracentral_Lobule) and by
1 - F/4 (age - 50) / 10 in every other region, and a male's by a further 1 + S in the temporal
lobes (Temporal_*): a regional decline with age, 4x steeper in front, and a sex difference, that
proportional scaling does not remove and a reference modelled on age and sex can (vpm compare
--covariates age,sex). The truth masks are unchanged by either (they follow the unscaled uptake).

Layout written (BIDS; truth under derivatives/):
  participants.tsv                 participant_id, group (normal|patient), seed, foci (the
                                   number planted: 0 for normals and --foci-free patients),
                                   age (years, one decimal), sex (F|M)
  sub-X/anat/sub-X_T1w.nii.gz      1 mm, the deformed Colin27 brain (skull-stripped), on
                                   Colin27's field of view grown by 12 mm a side
  sub-X/anat/sub-X_dseg.nii.gz     1 mm, the deformed AAL labels
  sub-X/pet/sub-X_pet.nii.gz       2 mm, float32 PET-like uptake
  derivatives/truth/sub-X_foci.nii.gz  patients: planted foci mask on the PET grid (focus id;
                                   all 0 for a --foci-free patient)
  derivatives/truth/foci.tsv       every planted focus: subject, id, template centre, radius, reduction
  derivatives/truth/sub-X_deformation.json  the deformation's parameters

Usage: synth_cohort.py --out DIR [--normals N] [--patients M] [--seed S] [--data DIR]
                       [--foci-per-patient K] [--foci-free F] [--reduction LO,HI]
                       [--age-effect F] [--sex-effect S] [--fwhm MM] [--noise F]
                       [--noise-fwhm MM] [--cortical] [--jobs J]
  --foci-free F      the last F of the M patients get no focus (0 <= F <= M; default 0)
  --reduction LO,HI  a focus lowers the uptake by a fraction drawn uniformly from [LO, HI]
                     (0 < LO <= HI < 1; default 0.15,0.30)
  --age-effect F     frontal uptake scaled by 1 - F (age - 50) / 10, other regions' by
                     1 - F/4 (age - 50) / 10 (0 <= F < 0.15; default 0: no effect)
  --sex-effect S     males' temporal uptake scaled by 1 + S (|S| < 0.3; default 0: no effect)
  --noise-fwhm MM    the noise's correlation length (0 <= MM <= 20; default 4; 0: white)
  --cortical         foci centred in the cerebral cortex only (default: any grey matter)
Exit 2 (one line on stderr) on a bad --foci-free, --reduction, --age-effect, --sex-effect or
--noise-fwhm or missing template data.
"""
import argparse
import concurrent.futures
import json
import multiprocessing
import os
import sys

import nibabel as nib
import numpy as np
from scipy import ndimage


def voxel_world(affine, shape):
    """World mm coordinates (3, *shape) of every voxel centre of a grid."""
    idx = np.indices(shape, dtype=np.float64).reshape(3, -1)
    w = affine[:3, :3] @ idx + affine[:3, 3:4]
    return w.reshape((3,) + tuple(shape))


def sample(volume, affine, world, order):
    """volume (with voxel->world `affine`) read at world points (3, ...); 0 outside."""
    inv = np.linalg.inv(affine)
    flat = world.reshape(3, -1)
    vox = inv[:3, :3] @ flat + inv[:3, 3:4]
    out = ndimage.map_coordinates(volume, vox, order=order, mode="constant", cval=0.0, prefilter=False)
    return out.reshape(world.shape[1:])


class Deformation:
    """pull(y): the template point a subject's native point y comes from."""

    def __init__(self, rng, centre, max_rotation_deg, max_scaling, bumps=6, width=25.0, displacement=4.0):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        angle = np.deg2rad(rng.uniform(-max_rotation_deg, max_rotation_deg))
        k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
        rot = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)
        scale = 1 + rng.uniform(-max_scaling, max_scaling, size=3)
        self.centre = np.asarray(centre, dtype=np.float64)
        self.linear = rot @ np.diag(1 / scale)
        self.width = width
        self.bump_centres = self.centre + rng.uniform(-45, 45, size=(bumps, 3))
        # |curl(phi a)| peaks near |a| / (width sqrt(e)): scale a for the displacement wanted
        self.potentials = rng.normal(size=(bumps, 3)) * displacement * width * np.sqrt(np.e) / np.sqrt(3)
        self.params = {"rotation_deg": float(np.rad2deg(angle)), "rotation_axis": axis.tolist(),
                       "scaling": scale.tolist(), "centre": self.centre.tolist(), "bump_width_mm": width,
                       "bump_centres": self.bump_centres.tolist(), "potentials": self.potentials.tolist()}

    def pull_grid(self, affine, shape, step=4):
        """pull at every voxel centre of a grid, computed exactly on a grid `step` voxels apart
        and interpolated (trilinear) in between: within 0.1 mm of pull() for step 4, 3x faster."""
        coarse = [(n - 1) // step + 2 for n in shape]
        caff = affine.copy()
        caff[:3, :3] = affine[:3, :3] * step
        xc = self.pull(voxel_world(caff, coarse))
        idx = np.indices(shape, dtype=np.float64).reshape(3, -1) / step
        out = np.stack([ndimage.map_coordinates(xc[k], idx, order=1, mode="nearest") for k in range(3)])
        return out.reshape((3,) + tuple(shape))

    def pull(self, y):
        """y: (3, ...) native world mm -> template world mm."""
        shape = y.shape
        y = y.reshape(3, -1)
        x = self.linear @ (y - self.centre[:, None]) + self.centre[:, None]
        for c, a in zip(self.bump_centres, self.potentials):
            d = y - c[:, None]
            phi = np.exp(-(d * d).sum(0) / (2 * self.width ** 2))
            grad = -d / self.width ** 2 * phi  # grad(phi); curl(phi a) = grad(phi) x a
            x += np.cross(grad.T, a).T
        return x.reshape(shape)


def uptake(t1, aal):
    """PET-like uptake of Colin27's tissue classes from its T1 intensity (0 outside the brain)."""
    gm = np.clip((t1 - 45) / 25, 0, 1) * np.clip((110 - t1) / 15, 0, 1)
    wm = np.clip((t1 - 95) / 15, 0, 1)
    u = 0.05 + 0.95 * gm + 0.3 * wm
    u[(aal > 0) & (t1 > 45) & (t1 < 100)] = np.maximum(u[(aal > 0) & (t1 > 45) & (t1 < 100)], 0.9)
    u[t1 <= 0] = 0
    return u


def grey_matter_points(t1, aal, affine):
    gm = (aal > 0) & (t1 > 55) & (t1 < 95)
    gm = ndimage.binary_erosion(gm, iterations=1)
    idx = np.argwhere(gm)
    return (affine[:3, :3] @ idx.T + affine[:3, 3:4]).T


def region_names(path):
    """AAL label -> region name from the atlas' name list (lines "LABEL NAME CODE")."""
    names = {}
    with open(path, encoding="utf-8", errors="replace") as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 2 and parts[0].isdigit():
                names[int(parts[0])] = parts[1]
    return names


def write(path, data, affine, dtype):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    img = nib.Nifti1Image(np.asarray(data, dtype=dtype), affine)
    img.set_qform(affine, code=1)
    img.set_sform(affine, code=1)
    tmp = path + ".part.nii.gz"
    nib.save(img, tmp)
    os.replace(tmp, path)


SHARED = {}
PAD_MM = 12
PET_VOXEL_MM = 2.0
# the AAL regions that are not cerebral cortex (--cortical keeps foci out of them), by name prefix
NOT_CORTEX = ("Caudate", "Putamen", "Pallidum", "Thalamus", "Hippocampus", "Amygdala", "Cerebelum", "Vermis")


def make_subject(subject, seed):
    """Writes one subject's images (and truth); returns its planted foci rows."""
    sid, group, nfoci, age, sex = subject
    g = SHARED
    a, t1, aal, aff, centre = g["args"], g["t1"], g["aal"], g["aff"], g["centre"]
    world_1mm, world_2mm, pet_aff = g["world_1mm"], g["world_2mm"], g["pet_aff"]
    r = np.random.default_rng(seed)
    deform = Deformation(r, centre, a.max_rotation, a.max_scaling)
    truth_template = np.zeros(t1.shape, dtype=np.float64)
    foci_rows = []
    pet_template = g["smoothed_base"]
    if a.age_effect or a.sex_effect:
        # the tissue uptake scaled by region, then smoothed to PET resolution (a no-op scale,
        # age 50 and female, gives smoothed_base itself)
        scale = np.ones(t1.shape, dtype=np.float64)
        scale[g["grey"]] = 1 - a.age_effect / 4 * (age - 50) / 10
        scale[g["frontal"]] = 1 - a.age_effect * (age - 50) / 10
        if sex == "M":
            scale[g["temporal"]] *= 1 + a.sex_effect
        pet_template = ndimage.gaussian_filter(g["base_uptake"] * scale, g["sigma_vox"])
        del scale
    if group == "patient":
        # a focus lowers the PET-resolution uptake by `reduction` over a ball (soft 2 mm edge),
        # so the reduction stated in foci.tsv is the one in the image, noise aside
        keep = np.ones(t1.shape, dtype=np.float64)
        for k in range(nfoci):  # 0 for a --foci-free patient: it draws nothing here
            radius = r.uniform(4.0, 10.0)
            inside = g["gm_points"][g["depth"] >= 0.8 * radius]  # at most a fifth of the ball outside the brain
            c = inside[r.integers(len(inside))]
            reduction = r.uniform(a.reduction_lo, a.reduction_hi)
            dist = np.sqrt(((world_1mm - c[:, None, None, None]) ** 2).sum(0))
            ball = np.clip((radius + 1.0 - dist) / 2.0, 0, 1)
            keep = np.minimum(keep, 1 - reduction * ball)
            truth_template[(dist <= radius) & (g["smoothed_base"] >= 0.4)] = k + 1
            foci_rows.append((f"sub-{sid}", k + 1, *np.round(c, 2), round(radius, 2), round(reduction, 3)))
        pet_template = pet_template * keep
    # native space: every native point reads the template through the deformation
    x1 = deform.pull_grid(g["native_aff"], g["native_shape"])
    # the T1 interpolated, cut to the template's brain carried voxel for voxel: interpolation
    # alone leaves small values up to a voxel outside the brain, and a mask of T1 > 0 would
    # grow every subject's brain by about 5 % (docs/register.md, "Two Dice measures")
    t1_native = sample(t1, aff, x1, order=1) * (sample((t1 > 0).astype(np.float64), aff, x1, order=0) > 0)
    aal_native = sample(aal, aff, x1, order=0)
    del x1
    x2 = deform.pull(world_2mm)
    pet = sample(pet_template, aff, x2, order=1)
    gscale = r.uniform(0.7, 1.3)
    coeff = r.normal(scale=0.015, size=3)  # a smooth bias of about 1.5 % per 80 mm
    rel = (world_2mm - centre[:, None, None, None]) / 80.0
    bias = 1 + np.tensordot(coeff, rel, axes=1)
    # noise correlated over a.noise_fwhm mm (4 by default: about 2 voxels; 0: white), std a.noise
    # of grey-matter uptake
    noise = r.normal(size=pet.shape)
    if a.noise_fwhm > 0:
        noise = ndimage.gaussian_filter(noise, a.noise_fwhm / 2.3548 / PET_VOXEL_MM)
    noise *= a.noise / noise.std()
    pet = (pet * bias + noise) * gscale
    base = os.path.join(a.out, f"sub-{sid}")
    write(os.path.join(base, "anat", f"sub-{sid}_T1w.nii.gz"), np.rint(t1_native), g["native_aff"], np.int16)
    write(os.path.join(base, "anat", f"sub-{sid}_dseg.nii.gz"), aal_native, g["native_aff"], np.int16)
    write(os.path.join(base, "pet", f"sub-{sid}_pet.nii.gz"), pet, pet_aff, np.float32)
    truth_dir = os.path.join(a.out, "derivatives", "truth")
    if group == "patient":
        truth = sample(truth_template, aff, x2, order=0)
        write(os.path.join(truth_dir, f"sub-{sid}_foci.nii.gz"), truth, pet_aff, np.uint8)
    params = dict(deform.params, seed=seed, global_scale=gscale, bias_gradient=coeff.tolist())
    with open(os.path.join(truth_dir, f"sub-{sid}_deformation.json"), "w") as f:
        json.dump(params, f, indent=1)
    print(f"synth_cohort: sub-{sid} ({group})", file=sys.stderr, flush=True)
    return foci_rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", required=True)
    ap.add_argument("--normals", type=int, default=8)
    ap.add_argument("--patients", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--data", default="/usr/share/mricron/templates")
    ap.add_argument("--foci-per-patient", type=int, default=2)
    ap.add_argument("--foci-free", type=int, default=0, help="the last K patients get no focus")
    ap.add_argument("--reduction", default="0.15,0.30",
                    help="LO,HI: the range a focus' uptake reduction is drawn from (default %(default)s)")
    ap.add_argument("--age-effect", type=float, default=0.0,
                    help="F: frontal uptake scaled by 1 - F (age - 50) / 10, elsewhere by a quarter of that")
    ap.add_argument("--sex-effect", type=float, default=0.0, help="S: males' temporal uptake scaled by 1 + S")
    ap.add_argument("--fwhm", type=float, default=8.0, help="PET resolution, mm")
    ap.add_argument("--noise", type=float, default=0.05, help="noise std relative to grey-matter uptake")
    ap.add_argument("--noise-fwhm", type=float, default=4.0,
                    help="the noise's correlation length, FWHM mm (0: white, independent per PET voxel)")
    ap.add_argument("--cortical", action="store_true",
                    help="foci centred in the cerebral cortex only (no deep grey matter, no cerebellum)")
    ap.add_argument("--max-rotation", type=float, default=5.0, help="degrees")
    ap.add_argument("--max-scaling", type=float, default=0.05)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="subjects generated at once")
    a = ap.parse_args()
    if a.normals < 0 or a.patients < 0 or a.normals + a.patients == 0:
        sys.exit("synth_cohort.py: --normals and --patients must be >= 0 and not both 0")
    if not 0 <= a.foci_free <= a.patients:
        print(f"synth_cohort.py: --foci-free {a.foci_free}: must be between 0 and --patients ({a.patients})",
              file=sys.stderr)
        sys.exit(2)
    try:
        a.reduction_lo, a.reduction_hi = (float(x) for x in a.reduction.split(","))
        ok = 0 < a.reduction_lo <= a.reduction_hi < 1
    except ValueError:
        ok = False
    if not ok:
        print(f"synth_cohort.py: --reduction '{a.reduction}': must be LO,HI with 0 < LO <= HI < 1",
              file=sys.stderr)
        sys.exit(2)
    if not 0 <= a.age_effect < 0.15:
        print(f"synth_cohort.py: --age-effect {a.age_effect:g}: must be >= 0 and < 0.15", file=sys.stderr)
        sys.exit(2)
    if not abs(a.sex_effect) < 0.3:
        print(f"synth_cohort.py: --sex-effect {a.sex_effect:g}: must be above -0.3 and below 0.3", file=sys.stderr)
        sys.exit(2)
    if not 0 <= a.noise_fwhm <= 20:
        print(f"synth_cohort.py: --noise-fwhm {a.noise_fwhm:g}: must be between 0 and 20 mm", file=sys.stderr)
        sys.exit(2)
    effects = bool(a.age_effect or a.sex_effect)
    need_names = effects or a.cortical
    for f in ("ch2bet.nii.gz", "aal.nii.gz") + (("aal.nii.txt",) if need_names else ()):
        if not os.path.exists(os.path.join(a.data, f)):
            print(f"synth_cohort.py: {os.path.join(a.data, f)}: not found (Debian's mricron-data ships it)",
                  file=sys.stderr)
            sys.exit(2)
    t1_img = nib.load(os.path.join(a.data, "ch2bet.nii.gz"))
    t1 = np.asarray(t1_img.dataobj, dtype=np.float64)
    aal = np.asarray(nib.load(os.path.join(a.data, "aal.nii.gz")).dataobj, dtype=np.float64)
    aff = t1_img.affine
    brain = np.argwhere(t1 > 0)
    centre = aff[:3, :3] @ brain.mean(0) + aff[:3, 3]
    base_uptake = uptake(t1, aal)
    gm_points = grey_matter_points(t1, aal, aff)
    depth_map = ndimage.distance_transform_edt(t1 > 0, sampling=np.abs(np.diag(aff)[:3]))
    inv = np.linalg.inv(aff)
    gm_vox = np.rint((inv[:3, :3] @ gm_points.T + inv[:3, 3:4]).T).astype(int)
    depth = depth_map[gm_vox[:, 0], gm_vox[:, 1], gm_vox[:, 2]]
    if a.cortical:  # focus centres only where the atlas says cerebral cortex
        names = region_names(os.path.join(a.data, "aal.nii.txt"))
        deep = [k for k, n in names.items() if n.startswith(NOT_CORTEX)]
        cortex = ~np.isin(aal[gm_vox[:, 0], gm_vox[:, 1], gm_vox[:, 2]], deep)
        gm_points, depth = gm_points[cortex], depth[cortex]
    sigma_vox = a.fwhm / 2.3548 / np.abs(np.diag(aff)[:3])
    world_1mm = voxel_world(aff, t1.shape)
    # native grids: Colin27's field of view grown by PAD_MM on every side (a deformed brain must
    # not touch the border), 1 mm for anatomy, 2 mm for PET
    native_shape = tuple(int(n + 2 * PAD_MM) for n in t1.shape)
    native_aff = aff.copy()
    native_aff[:3, 3] = aff[:3, 3] - aff[:3, :3] @ np.full(3, PAD_MM)
    pet_shape = tuple(int(np.ceil(n / 2)) for n in native_shape)
    pet_aff = native_aff.copy()
    pet_aff[:3, :3] = native_aff[:3, :3] * 2
    pet_aff[:3, 3] = native_aff[:3, 3] + native_aff[:3, :3] @ np.full(3, 0.5)  # 2 mm voxels cover the 1 mm grid
    world_2mm = voxel_world(pet_aff, pet_shape)
    regions = {}
    if effects:  # the AAL regions the age and sex effects scale, by name
        names = region_names(os.path.join(a.data, "aal.nii.txt"))
        frontal = [k for k, n in names.items()
                   if n.startswith(("Frontal", "Supp_Motor_Area", "Olfactory", "Rectus"))]
        temporal = [k for k, n in names.items() if n.startswith("Temporal")]
        if not frontal or not temporal:
            print(f"synth_cohort.py: {os.path.join(a.data, 'aal.nii.txt')}: no frontal or no temporal region names",
                  file=sys.stderr)
            sys.exit(2)
        regions = dict(grey=aal > 0, frontal=np.isin(aal, frontal), temporal=np.isin(aal, temporal))

    rng = np.random.default_rng(a.seed)
    os.makedirs(os.path.join(a.out, "derivatives", "truth"), exist_ok=True)
    subjects = [(f"N{i + 1:02d}", "normal", 0) for i in range(a.normals)] + \
               [(f"P{i + 1:02d}", "patient", a.foci_per_patient if i < a.patients - a.foci_free else 0)
                for i in range(a.patients)]
    seeds = [int(rng.integers(1 << 31)) for _ in subjects]
    # age and sex from a stream of their own: the images' seeds above are those of a cohort without them
    demo = np.random.default_rng([a.seed, 7])
    demographics = []
    for _ in subjects:
        age = round(float(demo.uniform(20, 80)), 1)
        demographics.append((age, "M" if demo.random() < 0.5 else "F"))
    subjects = [s + d for s, d in zip(subjects, demographics)]
    global SHARED
    SHARED = dict(args=a, t1=t1, aal=aal, aff=aff, centre=centre, base_uptake=base_uptake,
                  smoothed_base=ndimage.gaussian_filter(base_uptake, sigma_vox), sigma_vox=sigma_vox,
                  gm_points=gm_points, depth=depth, world_1mm=world_1mm, native_shape=native_shape, native_aff=native_aff,
                  world_2mm=world_2mm, pet_aff=pet_aff, **regions)
    jobs = max(1, min(a.jobs, len(subjects)))
    with concurrent.futures.ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as pool:
        results = list(pool.map(make_subject, subjects, seeds))
    rows = [(f"sub-{sid}", group, seed, nfoci, f"{age:.1f}", sex)
            for (sid, group, nfoci, age, sex), seed in zip(subjects, seeds)]
    foci_rows = [row for r in results for row in r]
    with open(os.path.join(a.out, "participants.tsv"), "w") as f:
        f.write("participant_id\tgroup\tseed\tfoci\tage\tsex\n")
        for row in rows:
            f.write("\t".join(map(str, row)) + "\n")
    with open(os.path.join(a.out, "derivatives", "truth", "foci.tsv"), "w") as f:
        f.write("participant_id\tfocus\tcentre_x\tcentre_y\tcentre_z\tradius_mm\treduction\n")
        for row in foci_rows:
            f.write("\t".join(map(str, row)) + "\n")
    description = f"seed {a.seed}, {a.normals} normals, {a.patients} patients"
    if a.foci_free:
        description += f" ({a.foci_free} without foci)"
    if (a.reduction_lo, a.reduction_hi) != (0.15, 0.30):
        description += f", uptake reduction {a.reduction_lo:g}-{a.reduction_hi:g}"
    if a.fwhm != 8.0:
        description += f", PET FWHM {a.fwhm:g} mm"
    if a.noise_fwhm != 4.0:
        description += ", white noise" if a.noise_fwhm == 0 else f", noise FWHM {a.noise_fwhm:g} mm"
    if a.cortical:
        description += ", foci in the cerebral cortex only"
    if a.age_effect:
        description += f", age_effect {a.age_effect:g} (frontal uptake x (1 - F (age - 50) / 10), elsewhere F/4)"
    if a.sex_effect:
        description += f", sex_effect {a.sex_effect:g} (males' temporal uptake x (1 + S))"
    with open(os.path.join(a.out, "dataset_description.json"), "w") as f:
        json.dump({"Name": "vpm synthetic cohort (Colin27 + AAL deformed, planted foci)",
                   "BIDSVersion": "1.8.0", "DatasetType": "raw",
                   "GeneratedBy": [{"Name": "vpm scripts/synth_cohort.py",
                                    "Description": description}]},
                  f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
