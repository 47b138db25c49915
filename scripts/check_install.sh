#!/usr/bin/env bash
# Installs the built vpm into a temporary prefix and builds + runs a consumer project that
# uses find_package(vpm). Usage: scripts/check_install.sh BUILD_DIR
set -euo pipefail
src="$(cd "$(dirname "$0")/.." && pwd)"
build="$(cd "$1" && pwd)"
work="$build/install-check"
rm -rf "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cmake -S "$src/tests/install_consumer" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" >/dev/null
LD_LIBRARY_PATH="$work/prefix/lib:${LD_LIBRARY_PATH:-}" "$work/build/consumer"
# the Python package, installed beside the library (python/CMakeLists.txt), imports from there
site=$(ls -d "$work"/prefix/lib/python3*/dist-packages 2>/dev/null | head -1 || true)
if [[ -n $site && -d $site/vpm ]]; then
  (cd "$work" && PYTHONPATH="$site" /usr/bin/python3 -c \
     'import os, vpm; assert vpm.__file__.startswith(os.getcwd()); print("installed Python package:", vpm.device_name("host"))')
fi
