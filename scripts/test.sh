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
# The builds and the tests' outputs take about 5 GiB here (the build 3.1, the sanitizer tree 0.7,
# the workflow tests' cohorts in the build); a file system that fills up mid-run shows as tests
# failing on files they wrote short, so say it first.
free_gib=$(df -P -k . | awk 'NR == 2 { print int($4 / 1048576) }')
if [[ -n $free_gib && $free_gib -lt 6 ]]; then
  echo "test.sh: warning: only $free_gib GiB free on $(df -P . | awk 'NR == 2 { print $6 }'); the builds and tests write about 5 GiB" >&2
fi
# In CI (or with SANITIZE=1): the quick part of the test suite again under ASan + UBSan, then a
# short fuzz pass over every reader in the same clang build (docs/robustness.md "Sanitizers" and
# "Fuzzing"); SANITIZE=full runs the whole suite under them (about an hour on 2 cores).
sanitize=false
if [[ "${SANITIZE:-${CI:-}}" == "true" || "${SANITIZE:-}" == "1" || "${SANITIZE:-}" == full ]]; then sanitize=true; fi
san_suite=ci
[[ "${SANITIZE:-}" != full ]] || san_suite=
san_pid=
if $sanitize; then
  # The sanitizer tree builds beside the normal build and its tests at the lowest priority: it
  # takes only the cores they leave idle (link steps, single-threaded tests, a test's waits).
  mkdir -p "${SAN_DIR:-build-san}"
  # It runs in a session of its own (setsid: one process group to stop on exit), which Linux
  # schedules as a group of its own (autogroup) with an equal share whatever its processes' nice
  # values: the group itself is niced first.
  SAN_SUITE=$san_suite SAN_PHASE=build setsid bash -c \
    'echo 19 2>/dev/null > /proc/self/autogroup || true; exec nice -n 19 bash scripts/sanitize.sh' \
    > "${SAN_DIR:-build-san}/build.log" 2>&1 &
  san_pid=$!
  trap '[[ -z $san_pid ]] || kill -- "-$san_pid" 2>/dev/null || true' EXIT
fi
# The benchmarks are not built here (scripts/build.sh builds them by default, and so does
# scripts/gpu/bundle.sh). With the sanitizer suite, the fuzz replays run there only (the same
# inputs, under ASan and UBSan).
replays=ON
if $sanitize; then replays=OFF; fi
bash scripts/build.sh -DVPM_BUILD_TESTS=ON -DVPM_BUILD_BENCH=${VPM_BUILD_BENCH:-OFF} -DVPM_FUZZ_REPLAYS=$replays
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
if $sanitize; then
  rc=0
  wait "$san_pid" || rc=$?
  san_pid=
  if [[ $rc -ne 0 ]]; then tail -40 "${SAN_DIR:-build-san}/build.log"; echo "test.sh: the sanitizer build failed" >&2; exit 1; fi
  phase "the rest of the sanitizer build (beside the others until then)"
  SAN_SUITE=$san_suite SAN_PHASE=test bash scripts/sanitize.sh
  phase "the sanitizer tests"
  FUZZ_NO_BUILD=1 FUZZ_SECONDS=${FUZZ_SECONDS:-4} bash scripts/fuzz.sh
  phase "the fuzz pass"
fi
