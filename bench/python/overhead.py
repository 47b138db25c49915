#!/usr/bin/python3
"""Python against C++ (issue 36's targets), in one run on one machine:

1. call overhead on the paper-size map: the demo's Colin27 mesh (ch2bet + AAL, `vpm mesh-image`'s
   default 5,000 target vertices) mapped by vpm.map_to_ball and by the same library call in C++
   (bench/map_call.cpp: validate_mesh + map_to_ball after a warm-up, in one process), blocks of
   RUNS calls interleaved ROUNDS times; medians. Also the overhead inside each Python call: its
   wall time minus the library's own time measured in the binding (report.seconds).
2. arrays of a 1M-tet mesh in and out: addresses (the mesh vpm works on has the arrays' memory,
   or a copy) and times (a view costs the same at any size, a copy grows with it).

Usage: PYTHONPATH=build/python /usr/bin/python3 bench/python/overhead.py --build build
           [--runs 5] [--rounds 2] [--out bench/results/python_overhead.json]
"""
import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np

import vpm

TEMPLATES = "/usr/share/mricron/templates"


def cube_mesh(n):
    """A structured mesh of n^3 cubes, 6 tets each (Kuhn split): 6 n^3 tets."""
    g = np.arange(n + 1, dtype=float)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    verts = np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)
    idx = lambda i, j, k: (i * (n + 1) + j) * (n + 1) + k
    i, j, k = [a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), np.arange(n), indexing="ij")]
    c = [idx(i + (b >> 2 & 1), j + (b >> 1 & 1), k + (b & 1)) for b in range(8)]
    paths = [(1, 3), (1, 5), (2, 3), (2, 6), (4, 5), (4, 6)]  # 0 -> a -> b -> 7
    tets = np.concatenate([np.stack([c[0], c[a], c[b], c[7]], axis=1) for a, b in paths]).astype(np.int32)
    return verts, tets


def timed(f, repeat=5):
    ts = []
    for _ in range(repeat):
        t = time.perf_counter()
        out = f()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), out


def overhead(build, runs, rounds, work):
    mesh_path = os.path.join(work, "colin27.vtu")
    if not os.path.exists(mesh_path):
        mesh, _ = vpm.mesh_image(f"{TEMPLATES}/ch2bet.nii.gz", labels=f"{TEMPLATES}/aal.nii.gz")
        vpm.write_mesh(mesh_path, mesh)
    mesh = vpm.read_mesh(mesh_path)
    arrays = (np.array(mesh.vertices), np.array(mesh.tets))
    cpp, py_mesh, py_arrays, inside = [], [], [], []
    vpm.map_to_ball(mesh)  # warm-up (the device's programs), as the C++ side's run 0
    for _ in range(rounds):
        r = subprocess.run([os.path.join(build, "bench", "vpm_bench_map_call"), mesh_path, str(runs)],
                           capture_output=True, text=True, check=True)
        cpp += json.loads(r.stdout)["seconds"]
        for _ in range(runs):
            t = time.perf_counter()
            _, rep = vpm.map_to_ball(mesh)
            py_mesh.append(time.perf_counter() - t)
            inside.append(py_mesh[-1] - rep.seconds)
            t = time.perf_counter()
            vpm.map_to_ball(*arrays)
            py_arrays.append(time.perf_counter() - t)
    med = statistics.median
    return {"mesh": {"vertices": mesh.num_vertices, "tets": mesh.num_tets, "path": mesh_path},
            "runs": runs * rounds, "cpp_s": cpp, "python_mesh_s": py_mesh, "python_arrays_s": py_arrays,
            "python_minus_library_s": inside,
            "median_cpp_s": med(cpp), "median_python_mesh_s": med(py_mesh), "median_python_arrays_s": med(py_arrays),
            "overhead_mesh_pct": 100 * (med(py_mesh) / med(cpp) - 1),
            "overhead_arrays_pct": 100 * (med(py_arrays) / med(cpp) - 1),
            "median_python_minus_library_s": med(inside)}


def zero_copy():
    verts, tets = cube_mesh(56)  # 185,193 vertices, 1,053,696 tets
    t_in, m = timed(lambda: vpm.Mesh(verts, tets), 3)
    own_v, own_t = m.vertices, m.tets
    t_view, v = timed(lambda: m.vertices, 20)
    t_back, addr = timed(lambda: vpm._vpm._mesh_addresses(own_v, own_t), 20)
    t_copy, addr_copy = timed(lambda: vpm._vpm._mesh_addresses(verts, tets), 5)
    ptr = lambda a: a.__array_interface__["data"][0]
    return {"vertices": int(verts.shape[0]), "tets": int(tets.shape[0]),
            "out": {"view_s": t_view, "same_address_each_time": ptr(v) == ptr(own_v),
                    "address_is_the_meshs": addr[0] == ptr(own_v)},
            "in": {"own_arrays_s": t_back, "own_arrays_no_copy": addr == (ptr(own_v), ptr(own_t)),
                   "foreign_arrays_s": t_copy, "foreign_arrays_copied": addr_copy[0] != ptr(verts),
                   "new_mesh_from_arrays_s": t_in}}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", default="build")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--work", default="out/bench-python")
    ap.add_argument("--out", default="bench/results/python_overhead.json")
    a = ap.parse_args()
    os.makedirs(a.work, exist_ok=True)
    res = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="minutes"),
           "machine": f"{platform.node()}, {os.cpu_count()} cores, {platform.processor() or platform.machine()}",
           "load_average": os.getloadavg(), "device": vpm.device_name(), "python": sys.version.split()[0],
           "overhead": overhead(a.build, a.runs, a.rounds, a.work), "zero_copy_1m": zero_copy()}
    res["load_average_after"] = os.getloadavg()
    o = res["overhead"]
    print(f"paper-size map ({o['mesh']['vertices']} vertices, {o['mesh']['tets']} tets), medians of {o['runs']}: "
          f"C++ {o['median_cpp_s']:.3f} s, Python (vpm.Mesh) {o['median_python_mesh_s']:.3f} s "
          f"({o['overhead_mesh_pct']:+.1f} %), Python (NumPy arrays) {o['median_python_arrays_s']:.3f} s "
          f"({o['overhead_arrays_pct']:+.1f} %); Python minus library inside the call {o['median_python_minus_library_s'] * 1e3:.3f} ms")
    z = res["zero_copy_1m"]
    print(f"1M-tet mesh ({z['tets']} tets): view {z['out']['view_s'] * 1e6:.1f} us, own arrays back in "
          f"{z['in']['own_arrays_s'] * 1e6:.1f} us (no copy: {z['in']['own_arrays_no_copy']}), foreign arrays "
          f"{z['in']['foreign_arrays_s'] * 1e3:.1f} ms (copied: {z['in']['foreign_arrays_copied']})")
    os.makedirs(os.path.dirname(a.out) or ".", exist_ok=True)
    json.dump(res, open(a.out, "w"), indent=1)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
