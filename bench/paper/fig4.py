#!/usr/bin/env python3
"""Fig. 4 of Hu, Zou & Hua 2014: a cut through the ball coloured by volume distortion at the
start of the volume-preserving map, midway and at the end.

Maps MESH (a tet mesh of a brain in native space, e.g. the demo's colin27.vtu) three times with
`vpm map`: --rounds 0 (the initial map: the start), --rounds 1 (one Moser round and its polish:
"midway"; vpm's Moser flow reaches the end state in its first round, so this panel equals the
last to the eye: the paper's midway, half-way through a round's flow, is not written by
`vpm map`) and the defaults (the end), then renders the plane z = 0 of each ball headlessly: every pixel is located
in the mapped mesh (VTK's probe filter, no display needed) and coloured by log(tet volume ratio)
of the tet holding it (blue: compressed, white: exact, red: expanded, clipped at +-0.5).

Usage: fig4.py VPM MESH WORK_DIR OUT.png [--size PIXELS]
Writes WORK_DIR/fig4_{start,midway,end}.vtu and .json, OUT.png, and OUT.json (each panel's
distortion, read from the maps' reports).
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import numpy_to_vtk, vtk_to_numpy

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from tables import png  # noqa: E402  (the same dependency-free PNG writer as Fig. 3)

STAGES = (("start", ["--rounds", "0"]), ("one_round", ["--rounds", "1"]), ("end", []))
CLIP = 0.5  # |log ratio| at full colour


def run_map(vpm, mesh, work, name, extra):
    out = os.path.join(work, f"fig4_{name}.vtu")
    report = os.path.join(work, f"fig4_{name}.json")
    cmd = [vpm, "map", mesh, "-o", out, "--report", report, "--quiet"] + extra
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode not in (0, 4):  # 4: converged false is still a map to show (the start is far)
        sys.exit(f"fig4: {' '.join(cmd)} exited {done.returncode}: {done.stderr.strip()}")
    with open(report) as f:
        return out, json.load(f)


def cut(path, size):
    """log(tet volume ratio) on a size x size grid of the plane z = 0 (NaN outside the mesh)."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(path)
    reader.Update()
    xs = np.linspace(-1, 1, size)
    x, y = np.meshgrid(xs, -xs)  # image rows top to bottom = +y to -y
    pts = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    poly = vtk.vtkPolyData()
    p = vtk.vtkPoints()
    p.SetData(numpy_to_vtk(pts.copy(), deep=True))
    poly.SetPoints(p)
    probe = vtk.vtkProbeFilter()
    probe.SetInputData(poly)
    probe.SetSourceData(reader.GetOutput())
    probe.Update()
    out = probe.GetOutput().GetPointData()
    ratio = vtk_to_numpy(out.GetArray("tet_volume_ratio")).astype(float)
    valid = vtk_to_numpy(out.GetArray(probe.GetValidPointMaskArrayName())).astype(bool)
    logr = np.full(ratio.shape, np.nan)
    ok = valid & (ratio > 0)
    logr[ok] = np.log(ratio[ok])
    return logr.reshape(size, size)


def colour(logr):
    """Diverging map: blue (-CLIP) - white (0) - red (+CLIP); light grey outside the mesh."""
    t = np.clip(np.nan_to_num(logr) / CLIP, -1, 1)[..., None]
    white, red, blue = np.array([255, 255, 255.0]), np.array([200, 30, 30.0]), np.array([30, 60, 200.0])
    rgb = np.where(t >= 0, white + t * (red - white), white - t * (blue - white))
    rgb[np.isnan(logr)] = (235, 235, 235)
    return rgb


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("vpm")
    ap.add_argument("mesh")
    ap.add_argument("work")
    ap.add_argument("out")
    ap.add_argument("--size", type=int, default=300)
    a = ap.parse_args()
    if not os.path.isfile(a.mesh):
        sys.exit(f"fig4: {a.mesh}: not found")
    os.makedirs(a.work, exist_ok=True)
    gap, bar = 12, 24
    panels, summary = [], {}
    for name, extra in STAGES:
        path, report = run_map(a.vpm, a.mesh, a.work, name, extra)
        panels.append(colour(cut(path, a.size)))
        final = report["final"]
        summary[name] = {k: final[k]["mean_abs_dev"] for k in ("vertex_volume_ratio", "tet_volume_ratio")}
    w = 3 * a.size + 4 * gap
    img = np.full((a.size + 3 * gap + bar, w, 3), 255.0)
    for i, p in enumerate(panels):
        x0 = gap + i * (a.size + gap)
        img[gap:gap + a.size, x0:x0 + a.size] = p
    # colour bar under the panels: log ratio from -CLIP (left) to +CLIP (right)
    ramp = np.linspace(-CLIP, CLIP, w - 2 * gap)[None, :].repeat(bar, 0)
    img[2 * gap + a.size:2 * gap + a.size + bar, gap:w - gap] = colour(ramp)
    png(a.out, img)
    with open(os.path.splitext(a.out)[0] + ".json", "w") as f:
        json.dump({"mesh": a.mesh, "stages": [s for s, _ in STAGES], "clip_log_ratio": CLIP, "maps": summary}, f,
                  indent=1)
    print(f"fig4: wrote {a.out}")


if __name__ == "__main__":
    main()
