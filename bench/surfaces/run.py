#!/usr/bin/python3
"""The surfaces benchmark (docs/surfaces.md): closed genus-0 triangle surfaces mapped to the unit
sphere by `vpm map SURFACE`, each run several times (medians), one row per surface with what a
user sees (exit status, face area mean |r-1| after the sphere map and after the polish, flipped
faces, seconds).

Usage: run.py OUT_DIR [--runs 3] [--surfaces colin27-22k,...] [--vpm build/vpm] [--timeout 600]
Writes OUT_DIR/surfaces.json and OUT_DIR/surfaces.md (and prints the table).

Surfaces, all from data Debian ships:
  colin27-22k, colin27-64k, colin27-128k  the boundary of Colin27's brain (mricron-data's
      ch2bet) meshed by `vpm mesh-image` at three densities
  aal-19k  the boundary of the union of AAL's regions (mricron-data's aal), a folded surface
  cgal-NAME  the closed genus-0 models of libcgal-demo (bench/shapes/run.py's MODELS), as they
      come (irregular triangles)
  colin27-patch-ears, colin27-patch  disk-like: the faces of colin27-22k whose centroid lies in
      the top 35 % of its height, as cut (with "ears": faces whose three corners are on the
      cut; `vpm map` splits them, SurfaceMapOptions::split_ears), and with the ears removed from
      the input; mapped to the unit disk
The split (docs/surfaces.md): defaults of the surface map were chosen on the DEVELOPMENT set
(aal-19k, cgal-cow, cgal-homer) and are reported on the others.
"""
import argparse
import json
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "shapes"))
from run import MODELS, extract_models, run  # noqa: E402  (bench/shapes/run.py)

TEMPLATES = "/usr/share/mricron/templates"  # Debian package mricron-data
BRAINS = {"colin27-22k": ("ch2bet.nii.gz", ["--target-vertices", "50000"]),
          "colin27-64k": ("ch2bet.nii.gz", ["--max-volume", "3.4"]),
          "colin27-128k": ("ch2bet.nii.gz", ["--max-volume", "1.2"]),
          "aal-19k": ("aal.nii.gz", ["--target-vertices", "30000"])}
DEVELOPMENT = {"aal-19k", "cgal-cow", "cgal-homer"}
PATCHES = ["colin27-patch-ears", "colin27-patch"]
DEFAULT = ",".join(list(BRAINS) + ["cgal-" + m for m in MODELS] + PATCHES)


def read_off(path):
    lines = [l for l in open(path).read().split("\n") if l.strip() and not l.startswith("#")]
    n, m = (int(x) for x in lines[1].split()[:2])
    v = [lines[2 + i].split()[:3] for i in range(n)]
    f = [[int(x) for x in lines[2 + n + i].split()[1:4]] for i in range(m)]
    return v, f


def write_off(path, v, f):
    used = sorted({i for t in f for i in t})
    new = {old: k for k, old in enumerate(used)}
    with open(path, "w") as o:
        o.write(f"OFF\n{len(used)} {len(f)} 0\n")
        o.writelines(" ".join(v[i]) + "\n" for i in used)
        o.writelines(f"3 {new[a]} {new[b]} {new[c]}\n" for a, b, c in f)


def patch(source, path, strip_ears):
    """The faces of `source` whose centroid is in the top 35 % of its height; without the faces
    whose three corners are on the cut when `strip_ears` (once)."""
    v, f = read_off(source)
    z = [float(p[2]) for p in v]
    cut = max(z) - 0.35 * (max(z) - min(z))
    f = [t for t in f if sum(z[i] for i in t) / 3 > cut]
    if strip_ears:
        edges = {}
        for t in f:
            for k in range(3):
                e = tuple(sorted((t[k], t[(k + 1) % 3])))
                edges[e] = edges.get(e, 0) + 1
        border = {i for e, c in edges.items() if c == 1 for i in e}
        f = [t for t in f if not all(i in border for i in t)]
    write_off(path, v, f)


def prepare(vpm, out, name, timeout):
    """OUT/NAME.off: the surface (meshed and its boundary taken, or extracted)."""
    path = os.path.join(out, name + ".off")
    if os.path.exists(path):
        return path
    if name.startswith("cgal-"):
        extract_models(out, [name[5:]])
        return path
    if name in PATCHES:
        patch(prepare(vpm, out, "colin27-22k", timeout), path, strip_ears=name == "colin27-patch")
        return path
    image, density = BRAINS[name]
    mesh = os.path.join(out, name + ".vtu")
    for cmd in ([vpm, "mesh-image", os.path.join(TEMPLATES, image), "-o", mesh, "--quiet"] + density,
                [vpm, "convert", mesh, path]):
        rc, _, last = run(cmd, timeout)
        if rc != 0:
            sys.exit(f"run.py: {' '.join(cmd)}: exit {rc}: {last}")
    os.remove(mesh)
    return path


def one(vpm, out, name, runs, timeout):
    surface = prepare(vpm, out, name, timeout)
    row = {"surface": name, "set": "development" if name in DEVELOPMENT else "report"}
    secs, reports = [], []
    for k in range(runs):
        report = os.path.join(out, f"{name}_map{k}.json")
        rc, s, last = run([vpm, "map", surface, "-o", os.path.join(out, name + "_sphere.vtp"), "--report", report,
                           "--quiet"], timeout)
        row.update(exit=rc, message=last)
        if rc not in (0, 4):
            return row
        secs.append(s)
        reports.append(json.load(open(report)))
    r = reports[-1]
    row.update(vertices=r["input"]["vertices"], faces=r["input"]["faces"], seconds=statistics.median(secs),
               seconds_all=[round(s, 2) for s in secs],
               sphere_map=r["initial"]["face_area_ratio"]["mean_abs_dev"],
               face=r["final"]["face_area_ratio"]["mean_abs_dev"],
               vertex=r["final"]["vertex_area_ratio"]["mean_abs_dev"],
               flipped=r["final"]["flipped_faces"], steps=len(r["rounds"]), stop=r["stop_reason"], domain=r["domain"],
               face_p99_log=r["final"]["face_area_ratio"]["p99_abs_log"],
               start=r.get("sphere_map", {}).get("start", "disk"),
               ears=r.get("disk_map", {}).get("ears"), split_edges=r.get("disk_map", {}).get("split_edges"),
               converged=r["converged"], polish_s=r["timings_s"]["polish"])
    return row


def table(rows, runs):
    lines = [f"| surface | set | vertices / faces | exit | start | face area \\|r-1\\|: sphere map (disk embedding) -> polished "
             f"| face p99 \\|log r\\| | vertex \\|r-1\\| | flipped | steps (stop) | s (median of {runs}) |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "face" not in r:
            lines.append(f"| {r['surface']} | {r['set']} | - | {r['exit']} | {r['message']} |||||||")
            continue
        lines.append(f"| {r['surface']} | {r['set']} | {r['vertices']:,} / {r['faces']:,} | {r['exit']} | {r['start']} | "
                     f"{100 * r['sphere_map']:.2f} % -> **{100 * r['face']:.2f} %** | {r['face_p99_log']:.2f} | "
                     f"{100 * r['vertex']:.2f} % | "
                     f"{r['flipped']} | {r['steps']} ({r['stop']}) | {r['seconds']:.2f} |")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--surfaces", default=DEFAULT)
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    vpm = os.path.abspath(a.vpm)
    rows = []
    for name in a.surfaces.split(","):
        rows.append(one(vpm, a.out, name, a.runs, a.timeout))
        print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    json.dump({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "runs": a.runs, "rows": rows},
              open(os.path.join(a.out, "surfaces.json"), "w"), indent=2)
    md = table(rows, a.runs)
    open(os.path.join(a.out, "surfaces.md"), "w").write(md + "\n")
    print(md)


if __name__ == "__main__":
    main()
