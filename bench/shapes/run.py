#!/usr/bin/python3
"""The shapes benchmark (issue 15; docs/shapes.md): genus-0 solids beyond brains meshed by
`vpm mesh-image` and mapped by `vpm map`, one row per shape and size, with the map's outcome as
a user sees it (exit status, converged, distortion, folds, time).

Usage: run.py OUT_DIR [--sizes 30k,300k] [--shapes limbs,hand,...] [--models cgal-hand,...]
       [--vpm build/vpm] [--timeout 600] [--check]
Writes OUT_DIR/shapes.json and OUT_DIR/shapes.md (and prints the table). --check (the quick
form the test suite runs, tests/CMakeLists.txt bench:shapes-quick) exits 1 naming every row that
misses the targets of the shapes that meet them: meshed, `vpm map` exit 0, fold-free, vertex
mean abs(r-1) <= 2 % and tet <= 8 %. Sizes: 30k (mesh-image's
default density, 26-32k tets) or any other Nk (--max-volume chosen from the 30k mesh's volume
for about N thousand tets: 150k, 300k; 30k runs first, or ran before in OUT_DIR).

--models adds public surface models that Debian's libcgal-demo ships (data.tar.gz, meshes/*.off;
only the closed genus-0 ones are listed in MODELS), meshed by `vpm mesh-image MODEL.off`;
--shapes none runs the models alone.
"""
import argparse
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
CGAL_DATA = "/usr/share/doc/libcgal-dev/data.tar.gz"  # Debian package libcgal-demo
# closed genus-0 surfaces of CGAL's data (Euler characteristic 2), name -> what it is
MODELS = {"hand": "a hand, fingers spread", "man": "a standing human figure", "camel": "a camel",
          "cow": "a cow", "triceratops": "a triceratops (horns, legs, tail)", "armadillo": "the Stanford armadillo",
          "bull": "a bull", "dino": "a dinosaur", "diplodocus": "a diplodocus (long neck and tail)",
          "homer": "a cartoon figure"}


def extract_models(out, names):
    """Writes OUT/cgal-NAME.off for each model name from libcgal-demo's data archive."""
    import tarfile
    if not os.path.exists(CGAL_DATA):
        sys.exit(f"run.py: {CGAL_DATA} not found: install Debian's libcgal-demo (scripts/setup.sh does)")
    with tarfile.open(CGAL_DATA) as tar:
        for n in names:
            if n not in MODELS:
                sys.exit(f"run.py: unknown model {n!r}: one of {', '.join(MODELS)}")
            data = tar.extractfile(f"data/meshes/{n}.off").read()
            open(os.path.join(out, f"cgal-{n}.off"), "wb").write(data)


def run(cmd, timeout):
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
        return p.returncode, time.time() - t0, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        return "timeout", time.time() - t0, f"killed after {timeout} s"


def off_extent(path):
    """Largest side of the bounding box of an .off surface."""
    lines = [l for l in open(path).read().split("\n") if l.strip() and not l.startswith("#")]
    n = int(lines[1].split()[0])
    pts = [[float(x) for x in lines[2 + k].split()[:3]] for k in range(n)]
    return max(max(p[a] for p in pts) - min(p[a] for p in pts) for a in range(3))


def one(vpm, out, shape, size, timeout):
    mask = os.path.join(out, f"{shape}.off" if shape.startswith("cgal-") else f"{shape}.nii.gz")
    base = os.path.join(out, f"{shape}_{size}")
    density = [] if size == "30k" else ["--max-volume", "__V__"]
    if density:
        volume = json.load(open(os.path.join(out, f"{shape}_30k_mesh.json")))["mesh"]["volume_mm3"]
        tets = 1000 * float(size.rstrip("k"))
        density[1] = f"{volume / tets * 2.2:.6g}"  # TetGen's tets average ~1/2.2 of the bound (measured)
    rc, secs, last = run([vpm, "mesh-image", mask, "-o", base + ".vtu", "--report", base + "_mesh.json"] + density, timeout)
    row = {"shape": shape, "size": size, "mesh_exit": rc, "mesh_s": round(secs, 2)}
    if rc == 2 and "self-intersects" in last and mask.endswith(".off"):
        # what the message tells a user to do: mesh the enclosed solid from a voxel mask
        row["voxelize_mm"] = voxel = off_extent(mask) / 250
        rc, secs, last = run([vpm, "mesh-image", mask, "-o", base + ".vtu", "--report", base + "_mesh.json",
                              "--voxelize", f"{voxel:.6g}"] + density, timeout)
        row.update(mesh_exit=rc, mesh_s=round(secs, 2), first_message=row.get("message"))
    if rc != 0:
        row["message"] = last
        return row
    mesh = json.load(open(base + "_mesh.json"))
    row.update(tets=mesh["mesh"]["tets"], vertices=mesh["mesh"]["vertices"],
               min_dihedral_deg=mesh["mesh"].get("min_dihedral_deg"))
    rc, secs, last = run([vpm, "map", base + ".vtu", "-o", base + "_ball.vtu", "--report", base + "_map.json"], timeout)
    row.update(map_exit=rc, map_s=round(secs, 2), message=last)
    if rc in (0, 4) and os.path.exists(base + "_map.json"):
        m = json.load(open(base + "_map.json"))
        f, i = m["final"], m["initial"]
        row.update(converged=m["converged"], reason=m["convergence"].get("reason"),
                   vertex=f["vertex_volume_ratio"]["mean_abs_dev"], tet=f["tet_volume_ratio"]["mean_abs_dev"],
                   folds=f["inverted_tets"], initial_vertex=i["vertex_volume_ratio"]["mean_abs_dev"],
                   initial_max_abs_log=i["tet_volume_ratio"]["max_abs_log"],
                   untangle_s=m["timings_s"].get("volume_map_untangle", 0))
    return row


CHECK_VERTEX, CHECK_TET = 0.02, 0.08  # the targets of the shapes benchmark (docs/shapes.md)


def misses(row):
    """What a row misses of --check's targets (empty: none)."""
    if row.get("mesh_exit") != 0:
        return f"mesh-image exit {row.get('mesh_exit')}: {row.get('message', '')}"
    if row.get("map_exit") != 0:
        return f"map exit {row.get('map_exit')}: {row.get('message', '')}"
    if row["folds"] != 0 or row["vertex"] > CHECK_VERTEX or row["tet"] > CHECK_TET:
        return f"{row['folds']} folds, vertex {100 * row['vertex']:.2f} %, tet {100 * row['tet']:.2f} %"
    return ""


def table(rows):
    lines = ["| shape | tets | exit | converged | vertex \\|r-1\\| | tet \\|r-1\\| | folds | initial map vertex / max \\|log r\\| | map s (untangle) |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        name = r['shape'] + (" (voxelized)" if r.get("voxelize_mm") else "")
        if "vertex" in r:
            lines.append(f"| {name} {r['size']} | {r['tets']:,} | {r['map_exit']} | {r['converged']}"
                         f"{'' if r['converged'] else ' (' + str(r['reason']) + ')'} | {100 * r['vertex']:.2f} % | "
                         f"{100 * r['tet']:.2f} % | {r['folds']} | {100 * r['initial_vertex']:.1f} % / "
                         f"{r['initial_max_abs_log']:.1f} | {r['map_s']:.1f} ({r['untangle_s']:.1f}) |")
        else:
            lines.append(f"| {name} {r['size']} | {r.get('tets', '-')} | mesh {r['mesh_exit']}, map "
                         f"{r.get('map_exit', '-')} | - | - | - | - | - | {r.get('map_s', '-')} | ")
            lines.append(f"|  | {r.get('message', '')} |||||||| ")
    return "\n".join(lines)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--sizes", default="30k")
    ap.add_argument("--shapes", default="limbs,hand,slab,coil,kidney,femur")
    ap.add_argument("--models", default="", help="libcgal-demo models: " + ",".join(MODELS) + " or all")
    ap.add_argument("--vpm", default=os.path.join(HERE, "..", "..", "build", "vpm"))
    ap.add_argument("--timeout", type=int, default=600)
    ap.add_argument("--check", action="store_true", help="exit 1 unless every row meets the targets")
    a = ap.parse_args()
    sizes = a.sizes.split(",")
    bad_size = [z for z in sizes if not re.fullmatch(r"[0-9]+(\.[0-9]+)?k", z)]
    if bad_size:
        ap.error(f"--sizes: {bad_size[0]}: not Nk (30k, 150k, 300k, ...)")
    os.makedirs(a.out, exist_ok=True)
    shapes = [] if a.shapes == "none" else a.shapes.split(",")
    missing = [s for s in shapes if not os.path.exists(os.path.join(a.out, f"{s}.nii.gz"))]
    if missing:
        subprocess.run(["/usr/bin/python3", os.path.join(HERE, "make_shapes.py"), a.out] + missing, check=True)
    models = list(MODELS) if a.models == "all" else [m for m in a.models.split(",") if m]
    if models:
        extract_models(a.out, models)
        shapes += ["cgal-" + m for m in models]
    rows = []
    for size in sorted(sizes, key=lambda z: z != "30k"):
        for s in shapes:
            rows.append(one(os.path.abspath(a.vpm), a.out, s, size, a.timeout))
            print(json.dumps(rows[-1]), file=sys.stderr, flush=True)
    json.dump({"date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "rows": rows},
              open(os.path.join(a.out, "shapes.json"), "w"), indent=2)
    md = table(rows)
    open(os.path.join(a.out, "shapes.md"), "w").write(md + "\n")
    print(md)
    if a.check:
        bad = [f"{r['shape']} {r['size']}: {m}" for r in rows if (m := misses(r))]
        for b in bad:
            print(f"run.py: {b}", file=sys.stderr)
        sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
