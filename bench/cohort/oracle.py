#!/usr/bin/python3
"""The planted-foci benchmark with a perfect registration: how much of what the element analysis
misses is the registration's fault, and how much the statistics' (bench/results/cohort_oracle/).

A synthetic subject (scripts/synth_cohort.py) is Colin27 read through a known deformation: its
native point y shows Colin27's point pull(y) (sub-X_deformation.json). So the ideal registered
ball of a subject puts each of its vertices (native position: the point field
original_position of its registered mesh) where Colin27's ball map puts pull(y): the template
ball mesh's positions interpolated (VTK probe, barycentric) at pull(y) in the template's native
mesh; a point outside that mesh takes the position of the closest point on it. Then the
workflow's own commands: `vpm sample` on these meshes and `vpm compare` for every patient, with
the same options as the workflow's run, and bench/cohort/evaluate.py scores the foci.

The ideal registration is not volume-preserving (the synthetic deformation is not exactly), and
a few of its tets may fold: sampling does not mind. It bounds what any registration can do for
this analysis; it is not a method.

Usage: oracle.py --bids DIR --results DIR --out DIR [--vpm build/vpm] [--jobs 2]
                 [--elements "--layout graded --level 4 --samples 64"]
                 [--compare "--normalisation proportional --threshold 3 --min-cluster 8 --extend 2.5 --sign hypo"]
Writes OUT/subjects/sub-X/sub-X_registered.vtu, OUT/tables, OUT/compare, OUT/evaluation.{json,md}.
"""
import argparse
import concurrent.futures
import json
import os
import shlex
import subprocess
import sys

import numpy as np
import vtk
from vtk.util import numpy_support as ns

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "scripts"))
from synth_cohort import Deformation  # noqa: E402
sys.path.insert(0, HERE)
from evaluate import read_participants  # noqa: E402


def fail(path, problem):
    print(f"oracle.py: {path}: {problem}", file=sys.stderr)
    sys.exit(2)


def read_vtu(path):
    if not os.path.isfile(path):
        fail(path, "not found")
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    if g.GetNumberOfPoints() == 0 or g.GetPointData().GetArray("original_position") is None:
        fail(path, "no points or no point field original_position")
    return g


def deformation(path):
    """The subject's Deformation from its json (pull(y): native mm -> Colin27 mm)."""
    try:
        with open(path) as f:
            p = json.load(f)
    except (OSError, ValueError) as e:
        fail(path, f"unreadable ({e})")
    d = Deformation.__new__(Deformation)
    axis = np.asarray(p["rotation_axis"], dtype=np.float64)
    angle = np.deg2rad(p["rotation_deg"])
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rot = np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * (k @ k)
    d.centre = np.asarray(p["centre"], dtype=np.float64)
    d.linear = rot @ np.diag(1 / np.asarray(p["scaling"], dtype=np.float64))
    d.width = float(p["bump_width_mm"])
    d.bump_centres = np.asarray(p["bump_centres"], dtype=np.float64)
    d.potentials = np.asarray(p["potentials"], dtype=np.float64)
    return d


class TemplateBall:
    """Colin27's ball position at any point of its native space."""

    def __init__(self, ball_path):
        ball = read_vtu(ball_path)
        native = vtk.vtkUnstructuredGrid()
        native.DeepCopy(ball)
        pts = vtk.vtkPoints()
        pts.SetData(ball.GetPointData().GetArray("original_position"))
        native.SetPoints(pts)
        b = ns.numpy_to_vtk(ns.vtk_to_numpy(ball.GetPoints().GetData()).copy(), deep=1)
        b.SetName("ball")
        native.GetPointData().AddArray(b)
        self.native = native
        self.ball = ns.vtk_to_numpy(ball.GetPoints().GetData())
        self.native_points = ns.vtk_to_numpy(pts.GetData())
        self.locator = vtk.vtkCellLocator()
        self.locator.SetDataSet(native)
        self.locator.BuildLocator()

    def at(self, x):
        """x: (n, 3) native mm -> (n, 3) ball positions; outside points: the closest point's."""
        poly = vtk.vtkPolyData()
        pts = vtk.vtkPoints()
        pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(x), deep=1))
        poly.SetPoints(pts)
        probe = vtk.vtkProbeFilter()
        probe.SetInputData(poly)
        probe.SetSourceData(self.native)
        probe.Update()
        out = probe.GetOutput()
        ball = ns.vtk_to_numpy(out.GetPointData().GetArray("ball")).copy()
        valid = ns.vtk_to_numpy(out.GetPointData().GetArray(probe.GetValidPointMaskArrayName()))
        cell = vtk.vtkGenericCell()
        closest = [0.0, 0.0, 0.0]
        cid, sub, d2 = vtk.reference(0), vtk.reference(0), vtk.reference(0.0)
        for i in np.flatnonzero(valid == 0):
            self.locator.FindClosestPoint(x[i].tolist(), closest, cell, cid, sub, d2)
            ids = self.native.GetCell(int(cid)).GetPointIds()
            v = [ids.GetId(k) for k in range(4)]
            p = self.native_points[v]
            # barycentric coordinates of the closest point in its tet, clamped
            lam = np.linalg.solve((p[1:] - p[0]).T, np.asarray(closest) - p[0])
            w = np.clip(np.concatenate([[1 - lam.sum()], lam]), 0, 1)
            ball[i] = w @ self.ball[v] / w.sum()
        return ball, int((valid == 0).sum())


def ideal_mesh(sub, bids, results, out, template):
    """Writes OUT/subjects/sub/sub_registered.vtu; returns (outside points, path)."""
    g = read_vtu(os.path.join(results, "subjects", sub, f"{sub}_registered.vtu"))
    y = ns.vtk_to_numpy(g.GetPointData().GetArray("original_position"))
    d = deformation(os.path.join(bids, "derivatives", "truth", f"{sub}_deformation.json"))
    x = d.pull(np.ascontiguousarray(y.T)).T
    ball, outside = template.at(x)
    # on the sphere: the boundary of the template's native mesh maps to it
    r = np.linalg.norm(ball, axis=1)
    ball[r > 1] /= r[r > 1, None]
    pts = vtk.vtkPoints()
    pts.SetData(ns.numpy_to_vtk(np.ascontiguousarray(ball), deep=1))
    g.SetPoints(pts)
    path = os.path.join(out, "subjects", sub, f"{sub}_registered.vtu")
    os.makedirs(os.path.dirname(path), exist_ok=True)
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(path + ".part.vtu")
    w.SetInputData(g)
    w.SetDataModeToAscii()
    if not w.Write():
        fail(path, "could not write")
    os.replace(path + ".part.vtu", path)
    return outside, path


def feature_image(bids, sub, folder, suffix):
    d = os.path.join(bids, sub, folder)
    for name in sorted(os.listdir(d)) if os.path.isdir(d) else []:
        if name.startswith(sub) and (name.endswith(f"_{suffix}.nii.gz") or name.endswith(f"_{suffix}.nii")):
            return os.path.join(d, name)
    fail(d, f"no {suffix} image of {sub}")


def run(cmd):
    p = subprocess.run(cmd, shell=True, capture_output=True, text=True)
    if p.returncode != 0:
        last = p.stderr.strip().splitlines()
        fail(cmd.split()[0], f"exit {p.returncode}: {last[-1] if last else 'no message'}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bids", required=True)
    ap.add_argument("--results", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--vpm", default="build/vpm")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--elements", default="--layout graded --level 4 --samples 64")
    ap.add_argument("--compare", default="--normalisation proportional --threshold 3 --min-cluster 10 --shrink 0.8 "
                                         "--extend 2.5 --smooth 0 --sign hypo")
    a = ap.parse_args()
    normals, patients = read_participants(a.bids)
    subs = normals + patients
    template = TemplateBall(os.path.join(a.results, "template", "template_ball.vtu"))
    outside = {}
    for sub in subs:
        outside[sub], _ = ideal_mesh(sub, a.bids, a.results, a.out, template)
    os.makedirs(os.path.join(a.out, "tables"), exist_ok=True)
    os.makedirs(os.path.join(a.out, "compare"), exist_ok=True)
    vpm = shlex.quote(os.path.abspath(a.vpm))

    def table(sub):
        return os.path.join(a.out, "tables", f"{sub}_pet.tsv")

    q = shlex.quote

    def sample(sub):
        # with an image covariate in the comparison (--image-covariate t1w), the T1w beside the PET
        mesh = os.path.join(a.out, "subjects", sub, f"{sub}_registered.vtu")
        images = f"pet={feature_image(a.bids, sub, 'pet', 'pet')}"
        if "--image-covariate t1w" in a.compare:
            images += f",t1w={feature_image(a.bids, sub, 'anat', 'T1w')}"
        run(f"{vpm} sample {q(mesh)} --images {q(images)} --subject {q(sub)} {a.elements} -o {q(table(sub))} --quiet")

    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        list(ex.map(sample, subs))
    normal_tables = ",".join(table(s) for s in normals)

    def compare(sub):
        mesh = os.path.join(a.out, "subjects", sub, f"{sub}_registered.vtu")
        labels = feature_image(a.bids, sub, "anat", "dseg")
        run(f"{vpm} compare --normals {q(normal_tables)} --patient {q(table(sub))} --feature pet {a.compare} "
            f"--mesh {q(mesh)} --image {q(feature_image(a.bids, sub, 'pet', 'pet'))} --labels {q(labels)} "
            f"-o {q(os.path.join(a.out, 'compare', sub + '_pet.tsv'))} --quiet")

    with concurrent.futures.ThreadPoolExecutor(a.jobs) as ex:
        list(ex.map(compare, patients))
    run(f"/usr/bin/python3 {q(os.path.join(HERE, 'evaluate.py'))} --bids {q(a.bids)} --results {q(a.out)} "
        f"--out-json {q(os.path.join(a.out, 'evaluation.json'))} --out-md {q(os.path.join(a.out, 'evaluation.md'))}")
    with open(os.path.join(a.out, "oracle.json"), "w") as f:
        json.dump({"points_outside_template_mesh": outside, "elements": a.elements, "compare": a.compare}, f, indent=1)
    with open(os.path.join(a.out, "evaluation.md")) as f:
        print(f.read())


if __name__ == "__main__":
    main()
