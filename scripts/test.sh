#!/usr/bin/env bash
# Sets up (Debian packages), builds and runs the whole test suite with ctest; in CI also the
# sanitizer build's test suite and a short fuzz pass (SANITIZE=1 asks for them outside CI).
set -euo pipefail
cd "$(dirname "$0")/.."
phase_start=$SECONDS
phase() { echo "test.sh: $1 took $((SECONDS - phase_start)) s"; phase_start=$SECONDS; }
bash scripts/setup.sh
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh -DVPM_BUILD_TESTS=ON
phase "set-up and build"
export POCL_CACHE_DIR="$PWD/$BUILD_DIR/pocl-cache"
mkdir -p "$POCL_CACHE_DIR"
# In CI the OpenCL device must exist: pin the ICD to PoCL and fail rather than skip.
if [[ "${CI:-}" == "true" ]]; then
  export OCL_ICD_VENDORS=/etc/OpenCL/vendors/pocl.icd
  export VPM_TEST_REQUIRE_OPENCL=1
fi
(cd "$BUILD_DIR" && ctest --output-on-failure -j"${JOBS:-2}" --timeout 900)
phase "the test suite"
# In CI (or with SANITIZE=1): the quick part of the test suite again under ASan + UBSan, then a
# short fuzz pass over every reader in the same clang build (docs/robustness.md "Sanitizers" and
# "Fuzzing"); SANITIZE=full runs the whole suite under them (about an hour on 2 cores).
if [[ "${SANITIZE:-${CI:-}}" == "true" || "${SANITIZE:-}" == "1" || "${SANITIZE:-}" == full ]]; then
  if [[ "${SANITIZE:-}" == full ]]; then bash scripts/sanitize.sh; else SAN_SUITE=ci bash scripts/sanitize.sh; fi
  phase "the sanitizer build and its tests"
  FUZZ_NO_BUILD=1 FUZZ_SECONDS=${FUZZ_SECONDS:-10} bash scripts/fuzz.sh
  phase "the fuzz pass"
fi
