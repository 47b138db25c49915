#!/usr/bin/env bash
# pip builds and installs the Python package from the source tree with Debian's tools, no
# network (setup.py), into a folder; a fresh Debian Python imports it from there and maps a mesh.
# The module is taken from BUILD_DIR (built already; setup.py builds its own build-pip/ when not
# told), so this checks the packaging, not a second compilation. Usage: scripts/check_pip.sh BUILD_DIR
set -euo pipefail
src="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "$1" && pwd)"
work="$build/pip-check"
rm -rf "$work"
mkdir -p "$work"
(cd "$src" && VPM_PIP_BUILD_DIR="${VPM_PIP_BUILD_DIR:-$build}" /usr/bin/python3 -m pip install --no-build-isolation --no-deps --no-index --target "$work/site" . \
   > "$work/pip.log" 2>&1) || { tail -30 "$work/pip.log"; echo "FAIL: pip install" >&2; exit 1; }
ls "$work/site/vpm/" | grep -q "^libvpm.so" || { echo "FAIL: libvpm.so not in the package" >&2; exit 1; }
cd "$work"
PYTHONPATH="$work/site" POCL_CACHE_DIR="${POCL_CACHE_DIR:-$build/pocl-cache}" /usr/bin/python3 - <<'PY'
import numpy as np
import vpm
assert vpm.__file__.startswith(__import__("os").getcwd()), vpm.__file__
print(vpm.devices()[0]["index"])
g = np.stack(np.meshgrid(*[np.arange(24)] * 3, indexing="ij"), -1).reshape(-1, 3)
data = (np.linalg.norm(g - 11.5, axis=1) < 9).reshape(24, 24, 24).astype(np.float32)
mesh, _ = vpm.mesh_image(data, affine=np.diag([2.0, 2.0, 2.0, 1.0]), target_vertices=300)
ball, report = vpm.map_to_ball(mesh)
assert report.final.inverted_tets == 0
print("pip-installed vpm: mapped", mesh.num_tets, "tets")
PY
echo "pip install: ok"
