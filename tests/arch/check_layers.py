#!/usr/bin/env python3
"""Fails when a host/<layer> file includes a header of a layer above its own, or when the layer
table of docs/architecture.md and the PUBLIC table below disagree.

The layers, lowest first, and the public headers (include/vpm/) each one implements. A file in
host/<layer>/ may include headers of its own layer and of the layers below it; host/with_<dep>/
files belong to the layer they serve (listed in WITH). Run from the repository root or give it.
"""
import pathlib
import re
import sys

LAYERS = ["core", "mesh", "io", "linalg", "image", "map", "register", "collective"]
PUBLIC = {
    "core": ["device", "placement", "error", "json", "timing", "format", "memory"],
    "mesh": ["mesh", "topology", "geometry", "validate", "metrics", "locate", "icosphere", "curvature", "mesh_stats", "labels", "mesh_order"],
    "io": ["io", "landmarks"],
    "linalg": ["sparse", "laplacian", "solver", "amg"],
    "image": ["image", "mesh_image", "mesh_image_report", "voxelize"],
    "map": ["initial_map", "untangle", "volume_map", "volume_map_peers", "polish", "ball_map", "surface_map"],
    "register": ["rbf", "registration", "dense_registration", "registration_preset", "transfer", "surface_registration"],
    "collective": ["collective", "elements", "element_sampler", "sampling", "covariates", "statistics", "tfce", "reference_sums", "calibration", "map_back", "cohort_view", "view_page", "label_names", "template_registration"],
}
WITH = {"with_tetgen": "image", "with_cgal": "image", "with_nifti": "image", "with_cholmod": "linalg", "with_gifti": "io"}


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


def documented_layers(root):
    """{layer: set of public headers} from the layer table of docs/architecture.md (rows
    "| layer | `host/layer` | owns | `header`, `header` |")."""
    table = {}
    for line in (root / "docs/architecture.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0] in LAYERS and cells[1] == f"`host/{cells[0]}`":
            table[cells[0]] = set(re.findall(r"`(\w+)`", cells[3]))
    return table


def table_problems(root):
    """Where docs/architecture.md's layer table and PUBLIC disagree."""
    doc = documented_layers(root)
    out = []
    for layer in LAYERS:
        if layer not in doc:
            out.append(f"docs/architecture.md: the layer table has no row for {layer}")
            continue
        code = set(PUBLIC[layer])
        for name in sorted(code - doc[layer]):
            out.append(f"docs/architecture.md: layer {layer} does not list vpm/{name}.hpp (tests/arch/check_layers.py does)")
        for name in sorted(doc[layer] - code):
            out.append(f"docs/architecture.md: layer {layer} lists vpm/{name}.hpp, which check_layers.py puts elsewhere or nowhere")
    return out


def main():
    root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    problems = table_problems(root)
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
