#!/usr/bin/python3
"""Synthesises a cohort with ground truth from the one labelled brain Debian ships (Colin27 and
its AAL atlas, mricron-data): normals and patients as a BIDS dataset, patients with planted
hypometabolic foci whose native-space masks are kept as the truth.

Each subject is Colin27 pulled through its own random, smooth, invertible deformation
(seeded): a rotation of up to --max-rotation degrees, an anisotropic scaling of up to
--max-scaling, and a divergence-free displacement (the curl of Gaussian vector potentials, so
volumes are kept to first order) of a few mm. Its PET-like image is the uptake of Colin27's
tissue classes (grey matter 1, white matter 0.3, CSF 0.05, from the T1 intensity) smoothed to
PET resolution (FWHM --fwhm mm); each patient's foci (balls of 8-20 mm diameter centred in grey
matter at least 0.8 radius deep, uptake at PET resolution lowered by 15-30 % inside, a soft 2 mm
edge) are planted in Colin27's space. The result is pulled into the subject's space on a 2 mm
grid, given a smooth multiplicative bias (about 1.5 % per 80 mm), spatially correlated Gaussian
noise (FWHM 4 mm, std --noise of grey-matter uptake) and a per-subject global scale (0.7-1.3).
The truth mask of a focus is its ball where the uptake is at least 0.4 (grey matter, mostly).

Layout written (BIDS; truth under derivatives/):
  participants.tsv                 participant_id, group (normal|patient), seed
  sub-X/anat/sub-X_T1w.nii.gz      1 mm, the deformed Colin27 brain (skull-stripped), on
                                   Colin27's field of view grown by 12 mm a side
  sub-X/anat/sub-X_dseg.nii.gz     1 mm, the deformed AAL labels
  sub-X/pet/sub-X_pet.nii.gz       2 mm, float32 PET-like uptake
  derivatives/truth/sub-X_foci.nii.gz  patients: planted foci mask on the PET grid (focus id)
  derivatives/truth/foci.tsv       every planted focus: subject, id, template centre, radius, reduction
  derivatives/truth/sub-X_deformation.json  the deformation's parameters

Usage: synth_cohort.py --out DIR [--normals N] [--patients M] [--seed S] [--data DIR]
                       [--foci-per-patient K] [--fwhm MM] [--noise F] [--jobs J]
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
NOISE_SIGMA_VOX = 4.0 / 2.3548 / 2  # FWHM 4 mm on the 2 mm grid


def make_subject(subject, seed):
    """Writes one subject's images (and truth); returns its planted foci rows."""
    sid, group = subject
    g = SHARED
    a, t1, aal, aff, centre = g["args"], g["t1"], g["aal"], g["aff"], g["centre"]
    world_1mm, world_2mm, pet_aff = g["world_1mm"], g["world_2mm"], g["pet_aff"]
    r = np.random.default_rng(seed)
    deform = Deformation(r, centre, a.max_rotation, a.max_scaling)
    truth_template = np.zeros(t1.shape, dtype=np.float64)
    foci_rows = []
    pet_template = g["smoothed_base"]
    if group == "patient":
        # a focus lowers the PET-resolution uptake by `reduction` over a ball (soft 2 mm edge),
        # so the reduction stated in foci.tsv is the one in the image, noise aside
        keep = np.ones(t1.shape, dtype=np.float64)
        for k in range(a.foci_per_patient):
            radius = r.uniform(4.0, 10.0)
            inside = g["gm_points"][g["depth"] >= 0.8 * radius]  # at most a fifth of the ball outside the brain
            c = inside[r.integers(len(inside))]
            reduction = r.uniform(0.15, 0.30)
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
    # noise correlated over about 2 voxels (FWHM 4 mm), std a.noise of grey-matter uptake
    noise = ndimage.gaussian_filter(r.normal(size=pet.shape), NOISE_SIGMA_VOX)
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
    ap.add_argument("--fwhm", type=float, default=8.0, help="PET resolution, mm")
    ap.add_argument("--noise", type=float, default=0.05, help="noise std relative to grey-matter uptake")
    ap.add_argument("--max-rotation", type=float, default=5.0, help="degrees")
    ap.add_argument("--max-scaling", type=float, default=0.05)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="subjects generated at once")
    a = ap.parse_args()
    if a.normals < 0 or a.patients < 0 or a.normals + a.patients == 0:
        sys.exit("synth_cohort.py: --normals and --patients must be >= 0 and not both 0")
    for f in ("ch2bet.nii.gz", "aal.nii.gz"):
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

    rng = np.random.default_rng(a.seed)
    os.makedirs(os.path.join(a.out, "derivatives", "truth"), exist_ok=True)
    subjects = [(f"N{i + 1:02d}", "normal") for i in range(a.normals)] + \
               [(f"P{i + 1:02d}", "patient") for i in range(a.patients)]
    seeds = [int(rng.integers(1 << 31)) for _ in subjects]
    global SHARED
    SHARED = dict(args=a, t1=t1, aal=aal, aff=aff, centre=centre, base_uptake=base_uptake,
                  smoothed_base=ndimage.gaussian_filter(base_uptake, sigma_vox), sigma_vox=sigma_vox,
                  gm_points=gm_points, depth=depth, world_1mm=world_1mm, native_shape=native_shape, native_aff=native_aff,
                  world_2mm=world_2mm, pet_aff=pet_aff)
    jobs = max(1, min(a.jobs, len(subjects)))
    with concurrent.futures.ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as pool:
        results = list(pool.map(make_subject, subjects, seeds))
    rows = [(f"sub-{sid}", group, seed) for (sid, group), seed in zip(subjects, seeds)]
    foci_rows = [row for r in results for row in r]
    with open(os.path.join(a.out, "participants.tsv"), "w") as f:
        f.write("participant_id\tgroup\tseed\n")
        for row in rows:
            f.write("\t".join(map(str, row)) + "\n")
    with open(os.path.join(a.out, "derivatives", "truth", "foci.tsv"), "w") as f:
        f.write("participant_id\tfocus\tcentre_x\tcentre_y\tcentre_z\tradius_mm\treduction\n")
        for row in foci_rows:
            f.write("\t".join(map(str, row)) + "\n")
    with open(os.path.join(a.out, "dataset_description.json"), "w") as f:
        json.dump({"Name": "vpm synthetic cohort (Colin27 + AAL deformed, planted foci)",
                   "BIDSVersion": "1.8.0", "DatasetType": "raw",
                   "GeneratedBy": [{"Name": "vpm scripts/synth_cohort.py",
                                    "Description": f"seed {a.seed}, {a.normals} normals, {a.patients} patients"}]},
                  f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
