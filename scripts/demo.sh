#!/usr/bin/env bash
# Sets up (Debian packages), builds, and runs `vpm demo` on the Colin27 brain shipped by
# Debian's mricron-data. Output in out/demo/ (override with the first argument).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh -DVPM_BUILD_TESTS=OFF -DVPM_BUILD_BENCH=OFF
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/$BUILD_DIR/pocl-cache}"
mkdir -p "$POCL_CACHE_DIR"
"$BUILD_DIR/vpm" demo --out "${1:-out/demo}"
