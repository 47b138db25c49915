#!/usr/bin/env bash
# bench/forces: the dense registration's forces (docs/register.md, "The image force") on the
# demo's subjects: `vpm_bench_pairs --seed S --max-rotation 10 --dense-force F [--incompressible]` for
# S = 0..SEEDS-1 (seed 0 without rotation: the demo's own subject), F in labels, image, both, the
# demo's deformations and their volume-preserving versions; one run each. Then
# bench/forces/summary.py writes bench/results/forces/{forces.json,forces.md}: medians over the
# seeds of the held-out Dice (labels through the maps), the volume bounds, the landmark regions'
# Dice, the registration's distortion and time.
# Usage: bash bench/forces/run.sh   (env: SEEDS=5, FORCES="labels image both", BUILD_DIR=build,
# EXTRA="more vpm_bench_pairs options", e.g. "--preset accurate", OUT=bench/results/forces;
# about 6 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${BUILD_DIR:-build}
SEEDS=${SEEDS:-5}
FORCES=${FORCES:-"labels image both"}
OUT=${OUT:-bench/results/forces}
EXTRA=${EXTRA:-}
WORK=${WORK:-$BUILD/forces-bench}
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/$BUILD/pocl-cache}
mkdir -p "$OUT" "$WORK"
uptime | tee "$OUT/load.txt"
for inc in "" "--incompressible"; do
  for force in $FORCES; do
    for ((seed = 0; seed < SEEDS; ++seed)); do
      rot=10
      [ "$seed" = 0 ] && rot=0
      dir="$WORK/${force}${inc:+_incompressible}_seed${seed}"
      if "$BUILD/bench/vpm_bench_pairs" --quiet --out "$dir" --seed "$seed" --max-rotation "$rot" --dense-force "$force" $inc $EXTRA \
        > "$dir.txt" 2>&1; then
        echo "forces: $force${inc:+ $inc} seed $seed done"
      else  # counted in the summary, never dropped silently
        echo "forces: $force${inc:+ $inc} seed $seed FAILED: $(tail -1 "$dir.txt")"
      fi
    done
  done
done
uptime | tee -a "$OUT/load.txt"
/usr/bin/python3 bench/forces/summary.py "$WORK" "$OUT"
