#!/usr/bin/env bash
# The synthetic cohort of ctest browser:view-cohort: 24 normals and 6 patients with foci at random
# places, derived from the results of ctest workflow:cohort by bench/view/synth_results.py, and
# its page with the data in a folder beside it (vpm view --data folder).
# Usage: synthetic_cohort.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1
build=$2
work=$build/test-view-cohort
rm -rf "$work"
mkdir -p "$work"
/usr/bin/python3 "$src/bench/view/synth_results.py" "$build/test-cohort/results" "$work/results" \
  --normals 24 --patients 6 --shapes 6 --seed 5 --vpm "$build/vpm" --jobs 2
mkdir -p "$work/results/view"
"$build/vpm" view "$work/results" --data folder --title "synthetic cohort (24 normals, 6 patients)" \
  -o "$work/results/view/cohort.html"
[[ -s $work/results/view/cohort_data/base.js ]] || { echo "FAIL: no data folder" >&2; exit 1; }
