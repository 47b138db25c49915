#!/usr/bin/env python3
"""Fails when a host/<layer> file includes a header of a layer above its own.

The layers, lowest first, and the public headers (include/vpm/) each one implements. A file in
host/<layer>/ may include headers of its own layer and of the layers below it; host/with_<dep>/
files belong to the layer they serve (listed in WITH). Run from the repository root or give it.
"""
import pathlib
import re
import sys

LAYERS = ["core", "mesh", "io", "linalg", "image", "map", "register", "collective"]
PUBLIC = {
    "core": ["device", "error", "json", "timing", "format"],
    "mesh": ["mesh", "topology", "geometry", "validate", "metrics", "locate", "icosphere", "mesh_stats", "labels", "mesh_order"],
    "io": ["io", "landmarks"],
    "linalg": ["sparse", "laplacian", "solver", "amg"],
    "image": ["image", "mesh_image", "mesh_image_report", "voxelize"],
    "map": ["initial_map", "untangle", "volume_map", "ball_map"],
    "register": ["rbf", "registration", "dense_registration"],
    "collective": ["collective", "elements", "sampling", "statistics", "map_back", "cohort_view", "view_page"],
}
WITH = {"with_tetgen": "image", "with_cgal": "image", "with_nifti": "image", "with_cholmod": "linalg"}


def layer_of_include(inc):
    m = re.match(r"vpm/(\w+)\.hpp$", inc)
    if m:
        for layer, names in PUBLIC.items():
            if m.group(1) in names:
                return layer
        return None
    m = re.match(r"(\w+)/[\w.]+$", inc)
    if m and m.group(1) in LAYERS:
        return m.group(1)
    if m and m.group(1) in WITH:
        return WITH[m.group(1)]
    return None


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    problems = []
    public = {p.stem for p in (root / "include/vpm").glob("*.hpp")}
    unmapped = public - {n for names in PUBLIC.values() for n in names}
    for name in sorted(unmapped):
        problems.append(f"include/vpm/{name}.hpp: not assigned to a layer in tests/arch/check_layers.py")
    for path in sorted((root / "host").rglob("*.[ch]pp")):
        folder = path.relative_to(root / "host").parts[0]
        own = WITH.get(folder, folder)
        if own not in LAYERS:
            problems.append(f"{path}: host/{folder} is not a layer")
            continue
        for n, line in enumerate(path.read_text().splitlines(), 1):
            m = re.match(r'#include "([^"]+)"', line)
            if not m:
                continue
            inc_layer = layer_of_include(m.group(1))
            if inc_layer and LAYERS.index(inc_layer) > LAYERS.index(own):
                problems.append(f"{path}:{n}: layer {own} includes {m.group(1)} of layer {inc_layer}")
    for p in problems:
        print(p)
    print(f"{len(problems)} layering problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
