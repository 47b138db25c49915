#!/usr/bin/env bash
# Sets up (Debian packages), builds, runs `vpm demo` on the Colin27 brain shipped by Debian's
# mricron-data (out/demo/, or the first argument), then the collective analysis on a small
# synthetic cohort through the Snakemake workflow (scripts/cohort_demo.sh: out/cohort/, or the
# second argument; skipped with VPM_DEMO_COHORT=0).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh -DVPM_BUILD_TESTS=OFF -DVPM_BUILD_BENCH=OFF
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/$BUILD_DIR/pocl-cache}"
mkdir -p "$POCL_CACHE_DIR"
"$BUILD_DIR/vpm" demo --out "${1:-out/demo}"
if [[ ${VPM_DEMO_COHORT:-1} != 0 ]]; then
  echo
  bash scripts/cohort_demo.sh "${2:-out/cohort}"
fi
