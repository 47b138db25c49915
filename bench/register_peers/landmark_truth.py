#!/usr/bin/python3
"""How far a `vpm_bench_pairs` run's landmarks and registration are from the ideal registration.

The pairs' landmarks are region centroids: the subject's in its mapped ball, paired with
Colin27's. A centroid is not a point correspondence under a nonlinear deformation (the
deformation does not commute with the mean), so a registration that pins the landmarks exactly
pins them where the truth does not put them. This script reads one run's folder (written by
`vpm_bench_pairs --out DIR`) and prints, in ball units:

* the registration's distance to the ideal registration (mean, p90), by radius and by scale
  (the error field averaged with a Gaussian of width s around each vertex, "smooth", and the
  rest);
* each landmark's ideal image (the ideal registration interpolated at the landmark in the
  subject's mapped mesh) against its target: how wrong the centroid pairs are.

The ideal positions come from subject_registered.vtu's point fields ideal_x, ideal_y, ideal_z.

usage: bench/register_peers/landmark_truth.py DIR
"""
import sys

import numpy as np
import vtk
from scipy.spatial import cKDTree
from vtk.util.numpy_support import vtk_to_numpy


def fail(message):
    print(f"landmark_truth.py: {message}", file=sys.stderr)
    sys.exit(2)


def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    if g.GetNumberOfPoints() == 0:
        fail(f"{path}: no points (missing or not a .vtu)")
    return g


def point_field(grid, path, name):
    a = grid.GetPointData().GetArray(name)
    if a is None:
        fail(f"{path}: no point field {name} (a vpm_bench_pairs run writes it)")
    return vtk_to_numpy(a)


def read_points_csv(path):
    try:
        return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")


def smooth(points, values, width, sample):
    """Gaussian average (width) of values around the sampled points."""
    tree = cKDTree(points)
    out = np.empty((len(sample), values.shape[1]))
    for k, (i, near) in enumerate(zip(sample, tree.query_ball_point(points[sample], 2 * width))):
        w = np.exp(-np.sum((points[near] - points[i]) ** 2, axis=1) / (2 * width * width))
        out[k] = w @ values[near] / w.sum()
    return out


def main():
    if len(sys.argv) != 2:
        fail("usage: landmark_truth.py DIR")
    d = sys.argv[1]
    ball_path, reg_path = f"{d}/subject_ball.vtu", f"{d}/subject_registered.vtu"
    ball, reg = read_vtu(ball_path), read_vtu(reg_path)
    mapped = vtk_to_numpy(ball.GetPoints().GetData()).astype(np.float64)
    registered = vtk_to_numpy(reg.GetPoints().GetData()).astype(np.float64)
    ideal = np.stack([point_field(reg, reg_path, f"ideal_{c}") for c in "xyz"], axis=1)
    if mapped.shape != registered.shape:
        fail(f"{ball_path} and {reg_path} differ in their points")
    error = registered - ideal
    e = np.linalg.norm(error, axis=1)
    print(f"registration to the ideal: mean {e.mean():.4f}, p90 {np.percentile(e, 90):.4f} ({len(e)} vertices)")
    r = np.linalg.norm(ideal, axis=1)
    for lo, hi in [(0, 0.5), (0.5, 0.8), (0.8, 0.97), (0.97, 1.01)]:
        m = (r >= lo) & (r < hi)
        if m.any():
            print(f"  radius {lo:.2f}-{hi:.2f}: {e[m].mean():.4f} ({m.sum()} vertices)")
    sample = np.arange(0, len(registered), 5)
    for s in (0.05, 0.1, 0.14, 0.2):
        sm = smooth(registered, error, s, sample)
        rest = np.linalg.norm(error[sample] - sm, axis=1).mean()
        print(f"  scale {s:.2f}: smooth part {np.linalg.norm(sm, axis=1).mean():.4f}, the rest {rest:.4f}")

    landmarks = read_points_csv(f"{d}/landmarks.csv")
    targets = read_points_csv(f"{d}/targets.csv")
    if landmarks.shape != targets.shape or landmarks.shape[1] != 3:
        fail(f"{d}: landmarks.csv and targets.csv differ in shape")
    locator = vtk.vtkCellLocator()
    locator.SetDataSet(ball)
    locator.BuildLocator()
    cells = vtk_to_numpy(ball.GetCells().GetConnectivityArray()).reshape(-1, 4)
    off = []
    for p, t in zip(landmarks, targets):
        cell = locator.FindCell(p)
        if cell < 0:
            continue
        corners = mapped[cells[cell]]
        b = np.linalg.solve((corners[1:] - corners[0]).T, p - corners[0])
        w = np.r_[1 - b.sum(), b]
        off.append(np.linalg.norm(w @ ideal[cells[cell]] - t))
    off = np.array(off)
    if off.size:
        print(f"landmarks' ideal images to their targets ({off.size} of {len(landmarks)}): mean {off.mean():.4f}, "
              f"median {np.median(off):.4f}, p90 {np.percentile(off, 90):.4f}, max {off.max():.4f}")


if __name__ == "__main__":
    main()
