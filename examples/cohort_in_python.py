#!/usr/bin/python3
"""vpm from Python, worked example (docs/python.md): map a brain to the unit ball, register
subjects to it, sample their PET images in the canonical volume elements, compare a patient with
the normals, and plot the map's volume distortion and the patient's z-map.

Runs headless (ctest python:example); examples/cohort_in_python.ipynb is made from it by
examples/make_notebook.py (one cell per "# %%" block).

    PYTHONPATH=build/python /usr/bin/python3 examples/cohort_in_python.py --out out/example
"""
# %% [markdown]
# # vpm from Python
# The template is Colin27 and its AAL atlas, as Debian's `mricron-data` ships them. The subjects
# are made by `scripts/synth_cohort.py` from the same brain through smooth random deformations,
# with PET-like images; the patient has two planted hypometabolic foci.

# %%
import argparse
import os
import subprocess
import sys

import matplotlib
if "ipykernel" not in sys.modules:
    matplotlib.use("Agg")  # headless
import matplotlib.pyplot as plt
import nibabel as nib
import numpy as np

import vpm

HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else os.getcwd()
TEMPLATES = "/usr/share/mricron/templates"
ap = argparse.ArgumentParser()
ap.add_argument("--out", default="out/example")
ap.add_argument("--target-vertices", type=int, default=3000)
ap.add_argument("--bids", help="a synthetic cohort made before (scripts/synth_cohort.py --normals 3 --patients 1) "
                "instead of making one in OUT/bids")
args = ap.parse_args([] if "ipykernel" in sys.modules else None)
os.makedirs(args.out, exist_ok=True)
print("devices:", [(d["index"], d["name"]) for d in vpm.devices() if d["selected"]])

# %% [markdown]
# ## Map a brain to the ball
# `mesh_image` meshes the brain mask with the atlas labels attached; `map_to_ball` is the whole
# `vpm map`: the fold-free initial map, then the volume-preserving flow.

# %%
template, _ = vpm.mesh_image(f"{TEMPLATES}/ch2bet.nii.gz", labels=f"{TEMPLATES}/aal.nii.gz",
                             target_vertices=args.target_vertices)
template_ball, report = vpm.map_to_ball(template, source="colin27")
print(f"Colin27: {template.num_vertices} vertices, {template.num_tets} tets; vertex mean |r-1| "
      f"{report.initial.vertex_volume_ratio.mean_abs_dev:.1%} -> {report.final.vertex_volume_ratio.mean_abs_dev:.2%}, "
      f"{report.final.inverted_tets} inverted, {report.seconds:.1f} s")

# %% [markdown]
# ## The distortion histogram
# Per-tet volume ratios of the ball map against the brain (1 = volume kept).

# %%
fig, ax = plt.subplots(figsize=(6, 3.5))
ax.hist(np.log2(template_ball.cell_data["tet_volume_ratio"]), bins=80, color="tab:blue")
ax.set_xlabel("log2 tet volume ratio (ball / brain)")
ax.set_ylabel("tets")
ax.set_title(f"Colin27 in the ball: tet mean |r-1| = {report.final.tet_volume_ratio.mean_abs_dev:.2%}")
fig.tight_layout()
fig.savefig(os.path.join(args.out, "distortion.png"), dpi=100)

# %% [markdown]
# ## Register subjects to it
# Three normals and a patient. Each is meshed and mapped like the template, then registered:
# the centroids of the AAL regions both carry, then dense iterations pulled by the region
# boundaries and the T1 images read through both maps.

# %%
bids = args.bids or os.path.join(args.out, "bids")
if not os.path.exists(os.path.join(bids, "participants.tsv")):
    subprocess.run(["/usr/bin/python3", os.path.join(HERE, "..", "scripts", "synth_cohort.py"), "--out", bids,
                    "--normals", "3", "--patients", "1", "--seed", "3", "--jobs", "2"], check=True)
subjects = ["sub-N01", "sub-N02", "sub-N03", "sub-P01"]
registered = {}
for s in subjects:
    t1, dseg = f"{bids}/{s}/anat/{s}_T1w.nii.gz", f"{bids}/{s}/anat/{s}_dseg.nii.gz"
    mesh, _ = vpm.mesh_image(t1, labels=dseg, target_vertices=args.target_vertices)
    ball, _ = vpm.map_to_ball(mesh, source=s)
    registered[s], r = vpm.register(ball, template=template_ball, dense_iterations=6, dense_force="both",
                                    image=t1, template_image=f"{TEMPLATES}/ch2bet.nii.gz")
    print(f"{s}: {r.landmarks} region centroids, landmark rms {r.landmark_rms_error:.1e}, "
          f"tet mean |r-1| against its map {r.metrics.tet_volume_ratio.mean_abs_dev:.2%}")

# %% [markdown]
# ## Sample the PET images in the elements, compare the patient with the normals

# %%
elements = vpm.elements(level=4, layout="graded", samples=32)
tables = {s: vpm.sample(registered[s], {"pet": f"{bids}/{s}/pet/{s}_pet.nii.gz"}, elements=elements, subject=s)
          for s in subjects}
c = vpm.compare([tables[s] for s in subjects[:3]], tables["sub-P01"], "pet", threshold=3, min_cluster=8,
                extend=2.5, sign="hypo", test="crawford-howell")
print(f"{len(elements)} elements; {len(c.clusters)} foci found in sub-P01 (|z| >= {c.threshold_used})")

# %% [markdown]
# ## The patient's z-map on its own PET grid
# Each voxel pushed into the ball through the patient's registered map; the planted foci are
# outlined.

# %%
pet_path = f"{bids}/sub-P01/pet/sub-P01_pet.nii.gz"
z = vpm.to_image(registered["sub-P01"], elements, np.nan_to_num(c.z), vpm.image(pet_path))
truth = np.asanyarray(nib.load(f"{bids}/derivatives/truth/sub-P01_foci.nii.gz").dataobj)
k = int(np.argmax((truth > 0).sum(axis=(0, 1)))) if truth.any() else z.shape[2] // 2
pet = np.asanyarray(nib.load(pet_path).dataobj)
fig, ax = plt.subplots(figsize=(5, 5))
ax.imshow(pet[:, :, k].T, origin="lower", cmap="gray")
im = ax.imshow(np.ma.masked_where(np.abs(z.data[:, :, k]) < 2, z.data[:, :, k]).T, origin="lower", cmap="coolwarm",
               vmin=-5, vmax=5)
if truth.any():
    ax.contour((truth[:, :, k] > 0).T, levels=[0.5], colors="yellow", linewidths=1)
fig.colorbar(im, ax=ax, label="z")
ax.set_title(f"sub-P01 PET, slice {k}: z (|z| >= 2), planted foci in yellow", fontsize=10)
fig.tight_layout()
fig.savefig(os.path.join(args.out, "zmap.png"), dpi=100)
print("wrote", os.path.join(args.out, "distortion.png"), "and", os.path.join(args.out, "zmap.png"))
