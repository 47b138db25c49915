#!/usr/bin/env bash
# Fuzzes every reader (docs/robustness.md "Fuzzing"): builds the libFuzzer targets of fuzz/ with
# ASan + UBSan in build-san/ (the tree of scripts/sanitize.sh), writes their seeds (fuzz_seeds:
# vpm's writers and tests/data), runs each target for FUZZ_SECONDS (or FUZZ_CPU_SECONDS) on one
# core, FUZZ_JOBS targets at a time, and writes FUZZ_OUT/summary.json (per target: executions,
# coverage, features, corpus, findings). Exits 1 when a target crashed, hung, leaked or ran out
# of memory; its input is in FUZZ_OUT/<target>/ (crash-*, timeout-*, leak-*, oom-*): fix the
# reader, then keep the input in fuzz/regressions/<target>/ (ctest fuzz:replay:<target> replays it
# in every build with the tests and VPM_FUZZ_REPLAYS, the default).
#   FUZZ_SECONDS  wall seconds per target (default 10)
#   FUZZ_CPU_SECONDS  instead: CPU seconds per target (a campaign on a busy machine; FUZZ_SECONDS
#                 then only caps the wall time, set it high)
#   FUZZ_JOBS     targets run at once, each on one core (default JOBS, else 2)
#   FUZZ_TARGETS  space-separated targets (default: all of fuzz/CMakeLists.txt)
#   FUZZ_OUT      logs, findings and summary.json (default build-san/fuzz-run)
#   FUZZ_CORPUS   a folder kept between runs (<target>/ under it; default: a fresh one in FUZZ_OUT)
#   FUZZ_MAX_LEN  largest input in bytes (default 16384)
#   FUZZ_TMPDIR   where the targets write their inputs (default /dev/shm when writable)
#   SAN_DIR       the build folder (default build-san); FUZZ_NO_BUILD=1 skips the build
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
SAN_DIR=${SAN_DIR:-build-san}
FUZZ_SECONDS=${FUZZ_SECONDS:-10}
FUZZ_JOBS=${FUZZ_JOBS:-${JOBS:-2}}
FUZZ_OUT=$(realpath -m "${FUZZ_OUT:-$SAN_DIR/fuzz-run}")
FUZZ_MAX_LEN=${FUZZ_MAX_LEN:-16384}
all=$(sed -n 's/^set(VPM_FUZZ_TARGETS \(.*\))$/\1/p' fuzz/CMakeLists.txt)
FUZZ_TARGETS=${FUZZ_TARGETS:-$all}
if [[ "${FUZZ_NO_BUILD:-}" != 1 ]]; then
  source scripts/sanitizers/configure.sh
  san_configure
  # shellcheck disable=SC2086
  cmake --build "$SAN_DIR" -j"${JOBS:-2}" --target fuzz_seeds $(printf 'fuzz_%s ' $FUZZ_TARGETS)
fi
source scripts/sanitizers/env.sh
# libFuzzer's runtime brings its own, unannotated std::vector<unsigned char> code: mixed with
# vpm's annotated vectors (_GLIBCXX_SANITIZE_VECTOR) ASan reports container-overflow where there
# is none (read_mgh's resize, found in the campaign; the replay of the same input under ASan
# without libFuzzer is clean). The check stays on in the sanitizer test suite and the replays.
export ASAN_OPTIONS="$ASAN_OPTIONS:detect_container_overflow=0"
# the targets write every input to a file: in memory (/dev/shm) that is 20x faster than on this
# machine's disk (label_names: 5,549 vs 252 executions a second)
if [[ -z "${FUZZ_TMPDIR:-}" && -d /dev/shm && -w /dev/shm ]]; then FUZZ_TMPDIR=/dev/shm; fi
export TMPDIR=${FUZZ_TMPDIR:-${TMPDIR:-/tmp}}
rm -rf "$FUZZ_OUT"
mkdir -p "$FUZZ_OUT"
"$SAN_DIR/fuzz/fuzz_seeds" "$FUZZ_OUT/seeds" tests/data
corpus_root=$(realpath -m "${FUZZ_CORPUS:-$FUZZ_OUT/corpus}")
# One target: its findings make $FUZZ_OUT/<target>/found.
fuzz_one() {
  local t=$1 dict=()
  mkdir -p "$FUZZ_OUT/$t" "$corpus_root/$t"
  [[ -f fuzz/dict/$t.dict ]] && dict=(-dict="$root/fuzz/dict/$t.dict")
  echo "fuzz: $t for ${FUZZ_SECONDS}s"
  # libFuzzer reads the corpus and the seeds, adds new inputs to the corpus (the first folder);
  # it runs in the target's output folder so that stray files land there
  if ! (cd "$FUZZ_OUT/$t" && nice -n 19 python3 "$root/scripts/fuzz_run.py" --record "$FUZZ_OUT/$t/cost.json" \
        --cpu "${FUZZ_CPU_SECONDS:-0}" -- "$root/$SAN_DIR/fuzz/fuzz_$t" -max_total_time="$FUZZ_SECONDS" \
        -timeout=10 -rss_limit_mb=2048 -max_len="$FUZZ_MAX_LEN" -print_final_stats=1 "${dict[@]}" \
        -artifact_prefix="$FUZZ_OUT/$t/" "$corpus_root/$t" "$FUZZ_OUT/seeds/$t" >"$FUZZ_OUT/$t/log" 2>&1); then
    echo "fuzz: $t FOUND A PROBLEM: $FUZZ_OUT/$t/log"
    grep -E "^(==[0-9]+==ERROR|SUMMARY|vpm fuzz:|.*runtime error)" "$FUZZ_OUT/$t/log" | head -5 || true
    touch "$FUZZ_OUT/$t/found"
  fi
}
running=0
for t in $FUZZ_TARGETS; do
  if ((running >= FUZZ_JOBS)); then wait -n || true; running=$((running - 1)); fi
  fuzz_one "$t" &
  running=$((running + 1))
done
wait
status=0
for t in $FUZZ_TARGETS; do [[ -f $FUZZ_OUT/$t/found ]] && status=1; done
python3 scripts/fuzz_summary.py "$FUZZ_OUT" "$corpus_root" $FUZZ_TARGETS > "$FUZZ_OUT/summary.json"
cat "$FUZZ_OUT/summary.json"
exit $status
