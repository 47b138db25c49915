#!/usr/bin/env bash
# Configures and builds vpm in build/ (Release, -j2). Extra arguments go to cmake.
# With the Python package built (pybind11 present), Debian's python3 is pointed at it: a .pth
# file in its site-packages names <build>/python, so `python3 -c "import vpm"` works from
# anywhere (the last build to run wins; VPM_PYTHON_PTH=0 skips it; PYTHONPATH=<build>/python
# does the same by hand).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$BUILD_DIR" -j"${JOBS:-2}"
if [[ ${VPM_PYTHON_PTH:-1} != 0 && -f $BUILD_DIR/python/vpm/__init__.py ]] && ls "$BUILD_DIR"/python/vpm/_vpm*.so >/dev/null 2>&1; then
  site=$(/usr/bin/python3 -c 'import site; print(site.getsitepackages()[0])')
  if mkdir -p "$site" 2>/dev/null && echo "$(cd "$BUILD_DIR/python" && pwd)" > "$site/vpm-build.pth" 2>/dev/null; then
    echo "build: python3 imports vpm from $BUILD_DIR/python ($site/vpm-build.pth)"
  else
    echo "build: $site is not writable: use PYTHONPATH=$BUILD_DIR/python to import vpm"
  fi
fi
