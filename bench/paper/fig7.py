#!/usr/bin/env python3
"""Fig. 7 of Hu, Zou & Hua 2014: a slice view of the registration, in the template's space.

Panels, one axial slice of Colin27 through the caudates and thalami (the held-out regions):
the template's T1 (reference), then the subject's T1 brought into the template's space through
the two maps without registration, after the landmark registration and after the dense one.
A template pixel p goes p -> template ball (the template's map) -> subject native (the subject's
registered ball mesh and its original_position) -> the subject's T1 there (trilinear). The
outline of the template's held-out regions (AAL caudate and thalamus) is drawn in red on every
panel, so how well each stage lines the subject up under it shows at a glance.

Usage: fig7.py LANDMARK_DIR DENSE_DIR OUT.png [--data /usr/share/mricron/templates]
  LANDMARK_DIR, DENSE_DIR: `vpm demo --out` folders of the same subject with --dense-iterations 0
  and the default (each with colin27_ball.vtu, subject_ball.vtu, subject_registered.vtu and
  subject_t1.nii.gz). Writes OUT.png and OUT.json (slice, panels).
"""
import argparse
import json
import os
import sys

import nibabel as nib
import numpy as np
import vtk
from scipy import ndimage
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tables import png  # noqa: E402

HELD_OUT = (71, 72, 77, 78)  # AAL caudate L/R, thalamus L/R


def read_mesh(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    if g.GetNumberOfPoints() == 0:
        sys.exit(f"fig7: {path}: no mesh")
    return g


def swapped(mesh, field="original_position"):
    """The mesh placed at its point field `field`, carrying its own points as point data 'other'."""
    g = vtk.vtkUnstructuredGrid()
    g.DeepCopy(mesh)
    other = vtk_to_numpy(mesh.GetPoints().GetData()).copy()
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(vtk_to_numpy(mesh.GetPointData().GetArray(field)).copy(), deep=True))
    g.SetPoints(pts)
    a = numpy_to_vtk(other, deep=True)
    a.SetName("other")
    g.GetPointData().AddArray(a)
    return g


def probe(source, points, name):
    """Point data `name` of `source` linearly interpolated at `points` (k x 3); NaN outside."""
    poly = vtk.vtkPolyData()
    p = vtk.vtkPoints()
    p.SetData(numpy_to_vtk(np.ascontiguousarray(points), deep=True))
    poly.SetPoints(p)
    f = vtk.vtkProbeFilter()
    f.SetInputData(poly)
    f.SetSourceData(source)
    f.Update()
    out = f.GetOutput().GetPointData()
    v = vtk_to_numpy(out.GetArray(name)).astype(float).reshape(len(points), -1)
    valid = vtk_to_numpy(out.GetArray(f.GetValidPointMaskArrayName())).astype(bool)
    v[~valid] = np.nan
    return v


def sample(img, world):
    """Trilinear value of a NIfTI image at world points (0 outside)."""
    vox = nib.affines.apply_affine(np.linalg.inv(img.affine), world)
    return ndimage.map_coordinates(np.asarray(img.dataobj, dtype=np.float32), vox.T, order=1, mode="constant")


def panel(values, outline, scale):
    g = np.clip(np.nan_to_num(values) / scale, 0, 1) * 255
    rgb = np.repeat(g[..., None], 3, axis=2)
    rgb[outline] = (230, 30, 30)
    return rgb


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("landmark_dir")
    ap.add_argument("dense_dir")
    ap.add_argument("out")
    ap.add_argument("--data", default="/usr/share/mricron/templates")
    a = ap.parse_args()
    for d in (a.landmark_dir, a.dense_dir):
        for f in ("colin27_ball.vtu", "subject_ball.vtu", "subject_registered.vtu", "subject_t1.nii.gz"):
            if not os.path.isfile(os.path.join(d, f)):
                sys.exit(f"fig7: {os.path.join(d, f)}: not found (run `vpm demo --out {d}`)")
    t1 = nib.load(os.path.join(a.data, "ch2bet.nii.gz"))
    aal = nib.load(os.path.join(a.data, "aal.nii.gz"))
    labels = np.asarray(aal.dataobj).astype(int)
    ijk = np.argwhere(np.isin(labels, HELD_OUT))
    z = float(nib.affines.apply_affine(aal.affine, ijk)[:, 2].mean())  # world mm through their middle
    brain = np.argwhere(np.asarray(t1.dataobj) > 0)
    wb = nib.affines.apply_affine(t1.affine, brain)
    (x0, y0), (x1, y1) = wb[:, :2].min(0), wb[:, :2].max(0)
    xs, ys = np.arange(x0, x1 + 1), np.arange(y1, y0 - 1, -1)  # 1 mm pixels, anterior up
    X, Y = np.meshgrid(xs, ys)
    world = np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, z)])
    shape = X.shape
    ref = sample(t1, world).reshape(shape)
    lab = ndimage.map_coordinates(labels, nib.affines.apply_affine(np.linalg.inv(aal.affine), world).T, order=0)
    held = np.isin(lab.reshape(shape), HELD_OUT)
    outline = held & ~ndimage.binary_erosion(held)
    # the template's map: native -> ball
    templ = swapped(read_mesh(os.path.join(a.landmark_dir, "colin27_ball.vtu")))
    ball = probe(templ, world, "other")
    panels = [("reference (Colin27)", ref)]
    for title, d, mesh in (("subject, maps only", a.landmark_dir, "subject_ball.vtu"),
                           ("landmarks", a.landmark_dir, "subject_registered.vtu"),
                           ("dense (boundaries + T1)", a.dense_dir, "subject_registered.vtu")):
        # the subject's ball mesh carries its native positions: ball -> native
        native = probe(read_mesh(os.path.join(d, mesh)), np.nan_to_num(ball), "original_position")
        v = sample(nib.load(os.path.join(d, "subject_t1.nii.gz")), np.nan_to_num(native)).reshape(shape)
        v[np.isnan(ball[:, 0]).reshape(shape) | np.isnan(native[:, 0]).reshape(shape)] = np.nan
        panels.append((title, v))
    scale = np.percentile(ref[ref > 0], 99)
    gap = 8
    h, w = shape
    img = np.full((h + 2 * gap, len(panels) * (w + gap) + gap, 3), 255.0)
    for i, (_, v) in enumerate(panels):
        img[gap:gap + h, gap + i * (w + gap):gap + i * (w + gap) + w] = panel(v, outline, scale)
    png(a.out, img.repeat(2, axis=0).repeat(2, axis=1))  # 0.5 mm screen pixels
    with open(os.path.splitext(a.out)[0] + ".json", "w") as f:
        json.dump({"slice_world_z_mm": z, "pixels": [int(h), int(w)], "panels": [t for t, _ in panels],
                   "outline_labels": list(HELD_OUT)}, f, indent=1)
    print(f"fig7: wrote {a.out}")


if __name__ == "__main__":
    main()
