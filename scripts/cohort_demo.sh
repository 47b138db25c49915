#!/usr/bin/env bash
# The collective analysis on a small synthetic cohort (docs/cohort.md): scripts/synth_cohort.py
# makes NORMALS normals and PATIENTS patients with planted hypometabolic foci from Colin27,
# the Snakemake workflow (workflow/Snakefile) meshes, maps, registers and samples every subject
# and compares each patient with the normals, and bench/cohort/evaluate.py scores the foci
# found against the planted truth (with the voxel-wise baseline beside them).
# Usage: cohort_demo.sh [OUT_DIR] (default out/cohort); env NORMALS (8), PATIENTS (2), SEED (1),
# MORE_FEATURES (modalities beside PET, default "{t1w: anat/T1w}"; "{}" for none),
# CORES (2), BUILD_DIR (build).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-out/cohort}
build=${BUILD_DIR:-build}
mkdir -p "$out"
more_features=${MORE_FEATURES:-"{t1w: anat/T1w}"}
out=$(cd "$out" && pwd)
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/$build/pocl-cache}"
want="normals=${NORMALS:-8} patients=${PATIENTS:-2} seed=${SEED:-1}"
if [[ ! -f $out/bids/participants.tsv || $(cat "$out/bids/.settings" 2>/dev/null) != "$want" ]]; then
  echo "cohort: synthesising $want into $out/bids" >&2
  rm -rf "$out/bids"
  /usr/bin/python3 scripts/synth_cohort.py --out "$out/bids" --normals "${NORMALS:-8}" --patients "${PATIENTS:-2}" \
    --seed "${SEED:-1}" --jobs "${CORES:-2}"
  echo "$want" > "$out/bids/.settings"
fi
# Snakemake's whole log goes to snakemake.log; its progress lines show here
if ! snakemake -s workflow/Snakefile --cores "${CORES:-2}" --directory "$out" \
    --config bids="$out/bids" out="$out/results" "more_features=$more_features" vpm="$PWD/$build/vpm" 2>&1 |
    tee "$out/snakemake.log" | grep --line-buffered -E "steps \(|^Nothing to be done"; then
  echo "cohort: no progress from the workflow" >&2
fi
if [[ ! -s $out/results/evaluation.md ]] || grep -q "^Error in rule\|Exiting because a job execution failed" "$out/snakemake.log"; then
  grep -A12 "^Error in rule" "$out/snakemake.log" >&2 || tail -20 "$out/snakemake.log" >&2
  echo "cohort: the workflow failed; see $out/snakemake.log and $out/results/logs/" >&2
  exit 3
fi
echo
echo "Cohort analysis ($want): per-element tables in $out/results/tables, each patient's z-map"
echo "and foci on its own PET grid in $out/results/compare (sub-*_pet_z.nii.gz, _foci.nii.gz,"
echo "_foci.tsv, _native.vtu). Foci found against the planted truth:"
echo
cat "$out/results/evaluation.md"
if [[ -s $out/results/view/cohort.html ]]; then
  echo
  echo "The cohort's coordinated table of brains (patients and normals, PET and z, the foci on each"
  echo "patient's own brain and slices; open it in a browser, from disk):"
  echo "  $out/results/view/cohort.html"
fi
