#!/usr/bin/env python3
"""A synthetic cohort's results folder, in the layout `vpm view` reads (docs/cohort.md), derived
from a real small cohort's results: for timing the page with hundreds or thousands of subjects,
which the real pipeline cannot run on a development machine (docs/view.md, "Performance").

What is real and what is not:
  * shapes: --shapes copies of the source's registered ball meshes, each native position moved by
    a random affine map (scale 0.92-1.08 per axis, rotation up to 6 degrees, shift up to 6 mm)
    and a smooth warp (up to 3 mm); subjects share these shapes round robin;
  * tables (in the source's format: HDF5 as the workflow writes them, or TSV with a sidecar):
    every element's value is the source normals' mean times a subject factor (0.8-1.2,
    which proportional scaling removes) times 1 + 5 % noise (iid and a smooth left-right,
    front-back gradient); patients get 1-3 planted hypometabolic foci (25-40 % lower over a ball
    of radius 0.15-0.25 in the unit ball, at radius 0.72-0.93) at random places;
  * comparisons: `vpm compare` run on them with the source comparison's options, so the foci,
    z-maps and foci tables are vpm's own; each patient's image and atlas are the source patient's
    (its slices show that image, with the synthetic patient's z-map pushed through its shape).

Usage: synth_results.py SRC_RESULTS OUT --normals N --patients P [--shapes S] [--seed K]
                        [--vpm BUILD/vpm] [--jobs J]
SRC_RESULTS: a workflow results folder (tables/, subjects/, compare/, template/), e.g. the one of
ctest workflow:cohort (build/test-cohort/results).
"""
import argparse
import concurrent.futures
import glob
import json
import os
import shutil
import subprocess
import sys
import zlib

import h5py
import numpy as np
import vtk
from vtk.util import numpy_support as ns


def read_table(path):
    with open(path) as f:
        head = f.readline().rstrip("\n").split("\t")
    data = np.loadtxt(path, delimiter="\t", skiprows=1, ndmin=2)
    return head, data


def write_table(path, head, data, sidecar, subject, mesh):
    fmt = ["%d" if h in ("element", "shell", "triangle", "samples") or h.endswith("_count") else "%.8g" for h in head]
    np.savetxt(path, data, delimiter="\t", header="\t".join(head), comments="", fmt=fmt)
    side = dict(sidecar, subject=subject, mesh=mesh)
    with open(path[:-4] + ".json", "w") as f:
        json.dump(side, f, indent=1)


def read_h5_feature(path, feature):
    with h5py.File(path, "r") as f:
        return np.asarray(f[f"features/{feature}/mean"], dtype=np.float64)


def read_h5_metadata(path):
    with h5py.File(path, "r") as f:
        return json.loads(f.attrs["metadata"])


def write_h5_table(path, source, feature, values, subject, mesh):
    """A copy of the HDF5 table `source` with `feature`'s means, subject and mesh replaced, and
    the digest line in its 512-byte user block written again (host/core/file_digest.hpp: the
    CRC-32 of every byte after the block), as vpm writes it."""
    shutil.copyfile(source, path)
    with h5py.File(path, "r+") as f:
        f[f"features/{feature}/mean"][...] = values.astype(np.float32)
        meta = json.loads(f.attrs["metadata"])
        meta.update(subject=subject, mesh=mesh)
        f.attrs["metadata"] = json.dumps(meta)
        f.attrs["subject"] = subject
    with open(path, "r+b") as f:
        data = f.read()
        line = b"vpm hdf5 crc32 %08x\n" % zlib.crc32(data[512:])
        f.seek(0)
        f.write(line + bytes(512 - len(line)))


def element_centres(vpm, definition, out):
    """Centres of the canonical elements in the unit ball (vpm elements)."""
    path = os.path.join(out, "elements.tsv")
    args = [vpm, "elements", "--layout", definition["layout"], "--level", str(definition["level"]),
            "--samples", str(definition["samples"]), "-o", path]
    if definition["layout"] == "shells":
        args += ["--shells", str(definition["shells"])]
    subprocess.run(args, check=True, capture_output=True)
    head, data = read_table(path)
    return data[:, [head.index("centre_x"), head.index("centre_y"), head.index("centre_z")]]


def subject_values(base, centres, rng, patient):
    """One subject's feature: base x factor x (1 + noise), patients with planted foci."""
    grad = rng.normal(0, 1, 3)
    noise = 0.04 * rng.normal(0, 1, len(base)) + 0.02 * (centres @ grad)
    x = base * rng.uniform(0.8, 1.2) * (1 + noise)
    foci = []
    if patient:
        for _ in range(rng.integers(1, 4)):
            d = rng.normal(0, 1, 3)
            c = d / np.linalg.norm(d) * rng.uniform(0.72, 0.93)
            r, red = rng.uniform(0.15, 0.25), rng.uniform(0.25, 0.4)
            t = np.clip(1 - np.linalg.norm(centres - c, axis=1) / r, 0, 1)
            x *= 1 - red * (t * t * (3 - 2 * t))
            foci.append((c.round(3).tolist(), round(r, 3), round(red, 3)))
    return x, foci


def perturbed_mesh(src, dst, rng):
    """The registered mesh `src` with its original_position moved by an affine map and a warp."""
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(src)
    r.Update()
    grid = r.GetOutput()
    arr = grid.GetPointData().GetArray("original_position")
    p = ns.vtk_to_numpy(arr).astype(np.float64)
    c = p.mean(axis=0)
    a, b, g = np.radians(rng.uniform(-6, 6, 3))
    rot = (np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]]) @
           np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]]) @
           np.array([[np.cos(g), -np.sin(g), 0], [np.sin(g), np.cos(g), 0], [0, 0, 1]]))
    q = (p - c) @ (rot * rng.uniform(0.92, 1.08, 3)).T
    k, ph = rng.uniform(0.02, 0.05, 3), rng.uniform(0, 2 * np.pi, 3)
    warp = rng.uniform(1, 3, 3) * np.sin(q[:, [1, 2, 0]] * k + ph)
    q = q + c + rng.uniform(-6, 6, 3) + warp
    out = ns.numpy_to_vtk(q.astype(np.float32 if arr.GetDataType() == vtk.VTK_FLOAT else np.float64), deep=1)
    out.SetName("original_position")
    grid.GetPointData().RemoveArray("original_position")
    grid.GetPointData().AddArray(out)
    w = vtk.vtkXMLUnstructuredGridWriter()
    w.SetFileName(dst)
    w.SetInputData(grid)
    w.SetDataModeToAppended()
    w.EncodeAppendedDataOff()
    if not w.Write():
        sys.exit(f"could not write {dst}")


def source_cohort(src):
    """The source's comparison sidecar, its normals' and its patient's tables."""
    sides = sorted(glob.glob(os.path.join(src, "compare", "*.json")))
    sides = [s for s in sides if "reference" in json.load(open(s))]
    if not sides:
        sys.exit(f"{src}/compare: no comparison sidecar")
    side = json.load(open(sides[0]))
    resolve = lambda p: p if os.path.isabs(p) else os.path.join(os.path.dirname(src), p)
    return side, [resolve(t) for t in side["reference"]["tables"]], resolve(side["patient"])


def as_tsv(vpm, path, scratch):
    """The table at `path` as TSV with its sidecar: the workflow's HDF5 tables exported (vpm convert)."""
    if not path.endswith(".h5"):
        return path
    tsv = os.path.join(scratch, os.path.basename(path)[:-3] + ".tsv")
    if not os.path.exists(tsv):
        subprocess.run([vpm, "convert", path, tsv, "--quiet"], check=True)
    return tsv


def compare(vpm, side, normals, patient, mesh, image, labels, out):
    o = side["options"]
    args = [vpm, "compare", "--normals", ",".join(normals), "--patient", patient, "--feature", side["reference"]["feature"],
            "--normalisation", side["reference"]["normalisation"], "--threshold", str(o["threshold"]),
            "--min-cluster", str(o["min_cluster"]), "--extend", str(o.get("extend", 0)), "--sign",
            {-1: "hypo", 1: "hyper"}.get(o["sign"], "both"), "--test", o.get("test", "z"),
            "--smooth", str(side["reference"].get("smoothing", 0)), "--mesh", mesh, "--image", image, "-o", out]
    if o.get("peak"):
        args += ["--peak", str(o["peak"])]
    if labels:
        args += ["--labels", labels]
    res = subprocess.run(args, capture_output=True, text=True)
    if res.returncode:
        sys.exit(f"vpm compare failed for {patient}: {res.stderr.strip()}")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("src")
    ap.add_argument("out")
    ap.add_argument("--normals", type=int, required=True)
    ap.add_argument("--patients", type=int, required=True)
    ap.add_argument("--shapes", type=int, default=24)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--vpm", default="build/vpm")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    src, out = os.path.abspath(a.src), os.path.abspath(a.out)
    side, src_normals, src_patient = source_cohort(src)
    feature = side["reference"]["feature"]
    for d in ("tables", "subjects", "compare", "template"):
        os.makedirs(os.path.join(out, d), exist_ok=True)
    # HDF5 sources (the workflow's) give HDF5 tables: a copy of a source table with the values
    # written in (the test suite's 30 subjects in 8 s instead of 35 with TSV)
    h5 = src_patient.endswith(".h5") and all(t.endswith(".h5") for t in src_normals)
    shutil.copy(os.path.join(src, "template", "template_ball.vtu"), os.path.join(out, "template", "template_ball.vtu"))
    if h5:
        sidecar, psidecar = read_h5_metadata(src_normals[0]), read_h5_metadata(src_patient)
        base = np.mean([read_h5_feature(t, feature) for t in src_normals], axis=0)
        meshes = [read_h5_metadata(t)["mesh"] for t in src_normals + [src_patient]]
    else:
        scratch = os.path.join(out, "source_tables")
        os.makedirs(scratch, exist_ok=True)
        src_normals = [as_tsv(a.vpm, t, scratch) for t in src_normals]
        src_patient = as_tsv(a.vpm, src_patient, scratch)
        head, first = read_table(src_normals[0])
        sidecar = json.load(open(src_normals[0][:-4] + ".json"))
        psidecar = json.load(open(src_patient[:-4] + ".json"))
        col = head.index(f"{feature}_mean")
        base = np.mean([read_table(t)[1][:, col] for t in src_normals], axis=0)
        meshes = [json.load(open(t[:-4] + ".json"))["mesh"] for t in src_normals + [src_patient]]
    centres = element_centres(a.vpm, sidecar["definition"], out)
    meshes = [m if os.path.isabs(m) else os.path.join(os.path.dirname(src), m) for m in meshes]
    shapes = []
    for j in range(a.shapes):
        dst = os.path.join(out, "subjects", f"shape-{j:02d}_registered.vtu")
        perturbed_mesh(meshes[j % len(meshes)], dst, rng)
        shapes.append(dst)
    planted, normals, patients = [], [], []
    for i in range(a.normals + a.patients):
        patient = i >= a.normals
        sid = f"sub-P{i - a.normals + 1:03d}" if patient else f"sub-N{i + 1:04d}"
        x, foci = subject_values(base, centres, rng, patient)
        if h5:
            path = os.path.join(out, "tables", f"{sid}_{feature}.h5")
            write_h5_table(path, src_patient if patient else src_normals[0], feature, x, sid, shapes[i % len(shapes)])
        else:
            data = first.copy()
            data[:, col] = x
            path = os.path.join(out, "tables", f"{sid}_{feature}.tsv")
            write_table(path, head, data, psidecar if patient else sidecar, sid, shapes[i % len(shapes)])
        (patients if patient else normals).append((sid, path, shapes[i % len(shapes)]))
        planted += [{"participant_id": sid, "centre_ball": c, "radius_ball": r, "reduction": red} for c, r, red in foci]
    image = psidecar["features"][0]["source"]
    labels = os.path.join(os.path.dirname(os.path.dirname(image)), "anat", os.path.basename(image).split("_")[0] + "_dseg.nii.gz")
    labels = labels if os.path.exists(labels) else None
    normal_tables = [p for _, p, _ in normals]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        jobs = [pool.submit(compare, a.vpm, side, normal_tables, p, m, image, labels,
                            os.path.join(out, "compare", f"{sid}_{feature}.tsv")) for sid, p, m in patients]
        for j in jobs:
            print("compared", j.result(), flush=True)
    with open(os.path.join(out, "synthetic.json"), "w") as f:
        json.dump({"source": src, "normals": a.normals, "patients": a.patients, "shapes": a.shapes, "seed": a.seed,
                   "planted_foci": planted}, f, indent=1)
    print(f"{out}: {a.normals} normals, {a.patients} patients, {a.shapes} shapes")


if __name__ == "__main__":
    main()
