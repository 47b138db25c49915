#!/usr/bin/env bash
# Runs on the GPU machine, from the repository root, out of the folder scripts/gpu/bundle.sh
# made (docs/gpu.md): the test suite with VPM_DEVICE=$DEV (less the install, architecture,
# workflow, browser, Python, h5py and shape-benchmark tests, which need tools a bare machine lacks), the solver and
# harmonic benchmarks, and `vpm map` of Colin27 at 1.1M and 10M tets (meshed there), last a 10M map with AMG-CG.
# Everything lands in $OUT/res.tgz, refreshed after each step, so a run cut short still returns
# what it did.
#   usage: bash .gpu/run.sh [STEPS (tests,bench,map1m,map10m,amg10m,extra; also sample, pairs)]
# (extra: the volume-map and registration benchmarks and `vpm demo`, about 30 s on an H200)
# DEVICE (gpu) and ICD_DIR (the bundle's NVIDIA vendor file) may be set for a dry run elsewhere,
# e.g. DEVICE=cpu ICD_DIR=/etc/OpenCL/vendors on a machine with PoCL.
set -u
R=$PWD
G=$(cd "$(dirname "$0")" && pwd)
W=/tmp/res
STEPS=${1:-tests,bench,map1m,map10m,amg10m,extra}
OUT=${OUT:-/tmp/out}
mkdir -p "$W" "$OUT"
save() { tar czf "$OUT/res.tgz" -C /tmp res 2>/dev/null; }
log() { echo "== $(date +%T) $*" | tee -a "$W/log.txt"; }
want() { [[ ",$STEPS," == *",$1,"* ]]; }
tar xJf "$G/libs.tar.xz" -C "$G"
tar xJf "$G/tests.tar.xz" -C "$G/build"
TV="$G/bin/time -v"
export LD_LIBRARY_PATH=$R/build:$G/lib OCL_ICD_VENDORS=${ICD_DIR:-$G/icd}
DEV=${DEVICE:-gpu}
mkdir -p build && cp -a "$G/build/." build/ && mkdir -p build/tests/tmp  # the tests write there
SRC=$(sed -n 's/^# Source directory: //p' build/CTestTestfile.cmake)
[[ -n $SRC && $SRC != "$R" ]] && grep -rl "$SRC" build --include=*.cmake | xargs sed -i "s#$SRC#$R#g"
mkdir -p /usr/share/mricron/templates && cp "$G"/mricron/* /usr/share/mricron/templates/
command -v ctest > /dev/null || export PATH=$PATH:/opt/torch/.venv/bin
log "root $R; $(nproc) cores; $(free -g | awk '/Mem/{print $2}') GB"
nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv >> "$W/log.txt" 2>&1
VPM_DEVICE=$DEV build/vpm devices >> "$W/log.txt" 2>&1 || { log "vpm devices failed"; cat "$W/log.txt"; save; exit 1; }
save
M=/usr/share/mricron/templates/ch2bet.nii.gz
MP=""
if want map10m || want amg10m; then
  ( $TV build/vpm mesh-image $M --max-volume 0.37 -o /tmp/colin_10m.vtu > "$W/mesh10m.txt" 2>&1 ) &
  MP=$!
fi
if want tests; then
  log "ctest${MP:+ (the 10M mesh being made beside it)}"
  VPM_DEVICE=$DEV VPM_TEST_REQUIRE_OPENCL=1 timeout 300 ctest --test-dir build -E "install|arch|workflow|browser|python|h5py|shapes-quick" \
    -j10 --timeout 200 --output-on-failure > "$W/ctest_gpu.log" 2>&1
  log "ctest rc $?"; grep -E "tests passed|tests failed" "$W/ctest_gpu.log" | tee -a "$W/log.txt"; save
fi
if want map1m || want bench; then
  $TV build/vpm mesh-image $M --max-volume 3.4 -o /tmp/colin_1m.vtu > "$W/mesh1m.txt" 2>&1
fi
[[ -n $MP ]] && { wait "$MP"; log "10M mesh made"; grep -h Elapsed "$W/mesh10m.txt" | tee -a "$W/log.txt"; }
# One map of MESH with OPTIONS, its report and output as map<LABEL>_gpu_<RUN>.json/.txt.
map_run() {  # LABEL MESH TIMEOUT RUN [OPTIONS...]
  local label=$1 mesh=$2 limit=$3 run=$4; shift 4
  log "map $label, run $run $*"
  VPM_DEVICE=$DEV $TV timeout "$limit" build/vpm map "$mesh" -o "/tmp/ball_$label.vtu" \
    --report "$W/map${label}_gpu_$run.json" "$@" > "$W/map${label}_gpu_$run.txt" 2>&1
  log "rc $?"; grep -h "Elapsed\|Maximum resident" "$W/map${label}_gpu_$run.txt" | tee -a "$W/log.txt"; save
}
# Two maps of MESH: the default, then with the sphere map's equal-area solves where the default
# does not put them (on a GPU the default solves boundaries of 50k+ vertices there: the 10M's).
maps() {  # LABEL MESH TIMEOUT SPHERE-SOLVE-OF-THE-SECOND-RUN
  map_run "$1" "$2" "$3" 1
  map_run "$1" "$2" "$3" 2 --sphere-solve "$4"
}
want map1m && maps 1m /tmp/colin_1m.vtu 120 device
want map10m && maps 10m /tmp/colin_10m.vtu 150 host
if want bench; then
  log "benchmarks"
  VPM_DEVICE=$DEV timeout 120 build/bench/vpm_bench_solver --sizes 100000,400000,1600000 --repeats 3 --no-hypre \
    --json "$W/solver_gpu.json" > "$W/solver_gpu.txt" 2>&1
  VPM_DEVICE=$DEV timeout 90 build/bench/vpm_bench_harmonic --sizes 400000,1600000 --repeats 3 --json "$W/harmonic_gpu.json" \
    /tmp/colin_1m.vtu > "$W/harmonic_gpu.txt" 2>&1
  TENM=""; want map10m && TENM=/tmp/colin_10m.vtu  # the sphere map, host Cholesky against device CG
  VPM_DEVICE=$DEV timeout 180 build/bench/vpm_bench_sphere_map --sizes "" --repeats 1 --json "$W/sphere_map_gpu.json" \
    /tmp/colin_1m.vtu $TENM > "$W/sphere_map_gpu.txt" 2>&1
  log "benchmarks done"; tail -4 "$W/sphere_map_gpu.txt" | tee -a "$W/log.txt"; save
fi
# --preconditioner auto keeps Jacobi on GPUs: this run says whether AMG would pay at 10M there
want amg10m && map_run 10m /tmp/colin_10m.vtu 150 amg --preconditioner amg
if want extra; then
  log "volume-map and registration benchmarks, vpm demo"
  VPM_DEVICE=$DEV timeout 200 build/bench/vpm_bench_register --runs 3 --out "$W/register_gpu.json" > "$W/register_gpu.txt" 2>&1
  VPM_DEVICE=$DEV timeout 200 build/bench/vpm_bench_volume_map --runs 3 --out /tmp/vm > "$W/vm_gpu.txt" 2>&1
  cp /tmp/vm/volume_map.json "$W/volume_map_gpu.json" 2>/dev/null
  VPM_DEVICE=$DEV timeout 200 build/vpm demo --out /tmp/demo > "$W/demo_gpu.txt" 2>&1
  cp /tmp/demo/demo.json "$W/demo_gpu.json" 2>/dev/null
  log "extra done"; tail -3 "$W/demo_gpu.txt" | tee -a "$W/log.txt"; save
fi
# step `sample`: `vpm sample` of Colin27's ball map (the default mesh, 214k tets) at level 6, graded,
# 8 samples, two images, three runs on the device and three on the host threads, alternated
if want sample; then
  log "vpm sample, level 6 graded"
  build/vpm mesh-image $M -o /tmp/ch2.vtu > "$W/sample_mesh.txt" 2>&1
  VPM_DEVICE=$DEV build/vpm map /tmp/ch2.vtu -o /tmp/ch2_ball.vtu --quiet >> "$W/sample_mesh.txt" 2>&1
  for run in 1 2 3; do
    for d in $DEV host; do
      VPM_DEVICE=$d $TV build/vpm sample /tmp/ch2_ball.vtu -o "/tmp/sample_$d.h5" --level 6 --layout graded --samples 8 \
        --images "pet=$M,t1w=/usr/share/mricron/templates/ch2.nii.gz" > "$W/sample_${d}_$run.txt" 2>&1
      log "sample $d run $run rc $?"; grep -h "Elapsed\|Maximum resident" "$W/sample_${d}_$run.txt" | tee -a "$W/log.txt"
    done
  done
  cmp /tmp/sample_$DEV.h5 /tmp/sample_host.h5 > /dev/null && log "sample tables identical" || log "sample tables differ"
  save
fi
# step `pairs`: the registration benchmark's pair (seed 1, volume-preserving, 10 degrees) through
# vpm_bench_pairs, once per setting of DEMO_CONFIGS ("VERTICES[:OPTIONS];..."), mesh + map + register
# timed by its report (bench/results/register_faster_dense/)
if want pairs; then
  IFS=';' read -ra CONFIGS <<< "${DEMO_CONFIGS:-5200;45000;45000:--preset accurate}"
  k=0
  for c in "${CONFIGS[@]}"; do
    v=${c%%:*}; opts=""; [[ $c == *:* ]] && opts=${c#*:}
    log "demo pair seed 1, $v vertices $opts"
    # shellcheck disable=SC2086
    VPM_DEVICE=$DEV timeout 200 build/bench/vpm_bench_pairs --out "/tmp/pair$k" --seed 1 --max-rotation 10 --incompressible \
      --target-vertices "$v" $opts > "$W/pair${k}_gpu.txt" 2>&1
    log "rc $?"; cp "/tmp/pair$k/demo.json" "$W/pair${k}_gpu.json" 2>/dev/null; save
    k=$((k + 1))
  done
fi
python3 - <<'PY' | tee -a "$W/log.txt"
import glob, json
for f in sorted(glob.glob("/tmp/res/map*.json")):
    r = json.load(open(f))
    print(f.split("/")[-1], "converged", r["converged"], "folds", r["final"]["inverted_tets"],
          "total %.2f s" % r["timings_s"]["total"], "sphere solver", r["initial_map"]["boundary"].get("density", {}).get("solver"),
          json.dumps(r["initial_map"]["timings_s"]))
PY
save; log end
