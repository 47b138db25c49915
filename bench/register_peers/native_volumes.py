"""The volume change of a registration measured as elastix's is: in native space, subject to template.

A registered subject's tet goes from the subject's native space (`original_position`) through its
registered ball position and the template's map (located in the template's ball mesh, the same
barycentric combination of the template's `original_position`) to the template's native space.
The ratio of the two native volumes is the registration's Jacobian determinant there, the
quantity elastix's `transformix -jac` writes per voxel; its mean |r - 1| weighted by the subject's
native tet volumes is comparable with elastix's mean |det J - 1| over the subject's brain voxels.
A volume-preserving deformation (the pairs' truth) has r = 1 up to the piecewise-linear
discretisation, whatever the two maps' own volume errors are; the ball measure of `vpm register`
(against the subject's own map) includes those.

usage: native_volumes.py SUBJECT_REGISTERED.vtu TEMPLATE_BALL.vtu [--ideal]
"""
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy


def read(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    return r.GetOutput()


def tet_volumes(x, tets):
    a, b, c, d = (x[tets[:, k]] for k in range(4))
    return np.einsum("ij,ij->i", b - a, np.cross(c - a, d - a)) / 6.0


def tets_of(grid):
    cells = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 4)
    return cells.astype(np.int64)


def carry_to_template(points, templ):
    """Template native positions of ball `points` through the template's ball mesh."""
    poly = vtk.vtkPolyData()
    pts = vtk.vtkPoints()
    pts.SetData(numpy_to_vtk(np.ascontiguousarray(points, dtype=float), deep=True))
    poly.SetPoints(pts)
    probe = vtk.vtkProbeFilter()
    probe.SetInputData(poly)
    probe.SetSourceData(templ)
    probe.Update()
    out = probe.GetOutput()
    native = vtk_to_numpy(out.GetPointData().GetArray("original_position")).copy()
    valid = vtk_to_numpy(out.GetPointData().GetArray(probe.GetValidPointMaskArrayName())).astype(bool)
    if not valid.all():  # the gap between the inscribed mesh and the sphere: the nearest tet, clamped
        loc = vtk.vtkStaticCellLocator()
        loc.SetDataSet(templ)
        loc.BuildLocator()
        tets = tets_of(templ)
        ball = vtk_to_numpy(templ.GetPoints().GetData())
        tnative = vtk_to_numpy(templ.GetPointData().GetArray("original_position"))
        for i in np.flatnonzero(~valid):
            cp = [0.0, 0.0, 0.0]
            cid, sub, d2 = vtk.reference(0), vtk.reference(0), vtk.reference(0.0)
            loc.FindClosestPoint(list(points[i]), cp, cid, sub, d2)
            t = tets[int(cid)]
            m = np.column_stack([ball[t[k]] - ball[t[0]] for k in (1, 2, 3)])
            b = np.linalg.solve(m, np.asarray(cp) - ball[t[0]])
            w = np.clip(np.concatenate([[1 - b.sum()], b]), 0, None)
            native[i] = (w / w.sum()) @ tnative[t]
    return native


def native_volume_change(registered_path, template_path, positions=None):
    """Mean |r - 1| (subject native volume weighted), the fraction of tets inverted, and r."""
    subj, templ = read(registered_path), read(template_path)
    tets = tets_of(subj)
    ball = vtk_to_numpy(subj.GetPoints().GetData()) if positions is None else positions
    native_s = vtk_to_numpy(subj.GetPointData().GetArray("original_position"))
    v_s = tet_volumes(native_s, tets)
    v_t = tet_volumes(carry_to_template(ball, templ), tets)
    r = v_t / v_s
    w = np.abs(v_s)
    return float((np.abs(r - 1) * w).sum() / w.sum()), float((r <= 0).mean()), r


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    subj = read(sys.argv[1])
    positions = None
    if "--ideal" in sys.argv:
        positions = np.stack([vtk_to_numpy(subj.GetPointData().GetArray(k)) for k in ("ideal_x", "ideal_y", "ideal_z")], 1)
    change, inverted, _ = native_volume_change(sys.argv[1], sys.argv[2], positions)
    print(f"native volume change {100 * change:.3f} %, inverted {100 * inverted:.4f} %")


if __name__ == "__main__":
    main()
