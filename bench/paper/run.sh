#!/usr/bin/env bash
# bench/paper: the experiments of Hu, Zou & Hua 2014 (Tables 1 and 2, Fig. 3) on this machine.
#   Table 1: build/bench/vpm_bench_paper (C++, the library directly: it deforms mesh vertices, which no
#            `vpm` command does, and needs the initial and the volume-preserving map of each mesh).
#   Table 2: `vpm_bench_pairs --seed S --max-rotation 10` with --dense-iterations 0 (landmarks only) and
#            12 (dense), seeds 0..SEEDS-1 (seed 0 without rotation: the demo's own subject).
#   Fig. 4: bench/paper/fig4.py maps the demo's Colin27 mesh three times and renders a cut of each
#            ball headlessly (bench/results/paper/fig4.png, fig4.json).
#   Fig. 7: bench/paper/fig7.py renders an axial slice of seed 0's subject brought into Colin27's
#            space through the maps (maps only, landmarks, dense) beside Colin27 (fig7.png).
#   Then bench/paper/tables.py writes bench/results/paper/{paper.json,paper.md,fig3.png}.
# Usage: bash bench/paper/run.sh   (env: SEEDS=5, BUILD_DIR=build; about 1.5-3 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/../.."
BUILD=${BUILD_DIR:-build}
SEEDS=${SEEDS:-5}
OUT=bench/results/paper
WORK=${WORK:-$BUILD/paper-bench}
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/$BUILD/pocl-cache}
mkdir -p "$OUT/table2" "$WORK"
uptime | tee "$OUT/load.txt"
nice "$BUILD/bench/vpm_bench_paper" --seeds "$SEEDS" --out "$OUT/table1.json" | tee "$OUT/table1.txt"
# the same with the flow twice as strong (largest displacement 12-20 % of the radius)
nice "$BUILD/bench/vpm_bench_paper" --seeds "$SEEDS" --amplitude 2 --out "$OUT/table1_x2.json" | tee -a "$OUT/table1.txt"
for ((seed = 0; seed < SEEDS; ++seed)); do
  rot=10
  [ "$seed" = 0 ] && rot=0
  for dense in 0 12; do
    dir="$WORK/seed${seed}_dense${dense}"
    rm -f "$OUT/table2/seed${seed}_dense${dense}.json" "$OUT/table2/seed${seed}_dense${dense}.failed"
    if nice "$BUILD/bench/vpm_bench_pairs" --quiet --out "$dir" --seed "$seed" --max-rotation "$rot" --dense-iterations "$dense" \
      > "$dir.txt" 2>&1; then
      cp "$dir/demo.json" "$OUT/table2/seed${seed}_dense${dense}.json"
      echo "table 2: seed $seed, dense iterations $dense done"
    else  # kept and counted in the table, never dropped silently
      cp "$dir.txt" "$OUT/table2/seed${seed}_dense${dense}.failed"
      echo "table 2: seed $seed, dense iterations $dense FAILED: $(tail -1 "$dir.txt")"
    fi
  done
done
# Fig. 4: a cut through the ball coloured by log tet volume ratio (start, one round, end) of the
# demo's Colin27 mesh
nice /usr/bin/python3 bench/paper/fig4.py "$BUILD/vpm" "$WORK/seed0_dense0/colin27.vtu" "$WORK/fig4" "$OUT/fig4.png"
# Fig. 7: a slice of the demo's subject in Colin27's space: maps only, landmarks, dense
/usr/bin/python3 bench/paper/fig7.py "$WORK/seed0_dense0" "$WORK/seed0_dense12" "$OUT/fig7.png"
uptime | tee -a "$OUT/load.txt"
/usr/bin/python3 bench/paper/tables.py "$OUT"
