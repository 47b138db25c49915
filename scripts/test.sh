#!/usr/bin/env bash
# Sets up (Debian packages), builds and runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
BUILD_DIR=${BUILD_DIR:-build}
export BUILD_DIR
bash scripts/build.sh -DVPM_BUILD_TESTS=ON
export POCL_CACHE_DIR="$PWD/$BUILD_DIR/pocl-cache"
mkdir -p "$POCL_CACHE_DIR"
# In CI the OpenCL device must exist: pin the ICD to PoCL and fail rather than skip.
if [[ "${CI:-}" == "true" ]]; then
  export OCL_ICD_VENDORS=/etc/OpenCL/vendors/pocl.icd
  export VPM_TEST_REQUIRE_OPENCL=1
fi
cd "$BUILD_DIR"
ctest --output-on-failure -j"${JOBS:-2}" --timeout 900
