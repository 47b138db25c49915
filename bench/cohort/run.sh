#!/usr/bin/env bash
# The planted-foci benchmark (docs/cohort.md): synthesise a cohort, run the whole workflow on it
# with CORES cores, score the foci against the truth, run the individual-analysis peer (voxel-wise
# after elastix, bench/cohort/voxelwise_elastix.py, CORES subjects at a time; skipped with a note when
# elastix is not on PATH) and summarise time and memory per rule.
# Usage: bench/cohort/run.sh OUT_DIR [NORMALS=50] [PATIENTS=10] [SEED=1]; env MORE_FEATURES (default
# "{t1w: anat/T1w}"), REGISTER (the workflow's register settings, e.g. "{extra: '--dense-iterations 12',
# force: labels}"; default the config's), MESH (the meshes, e.g. "{target_vertices: 15000}"), CORES (2),
# BUILD_DIR (build), PEER_SETTINGS (the peer's --settings, default its own "8,3,340,0"), FOCI_FREE
# (synth_cohort.py --foci-free: the last K patients planted with no focus; default 0) and REDUCTION
# (synth_cohort.py --reduction LO,HI, e.g. "0.10,0.20"; default 0.15,0.30), AGE_EFFECT and SEX_EFFECT
# (synth_cohort.py --age-effect F, --sex-effect S: frontal uptake declining with age, males' temporal
# uptake raised; default 0, none), FWHM (--fwhm, the PET's resolution in mm; default 8), NOISE_FWHM
# (--noise-fwhm: 0 for white noise; default 4), CORTICAL (1: --cortical, foci in the cerebral cortex
# only) and FOCI_PER_PATIENT (--foci-per-patient; default 2), all read only when the cohort is synthesised (no
# OUT_DIR/bids/participants.tsv yet). Writes OUT_DIR/summary.json and OUT_DIR/summary.md (and prints
# the latter).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=$1
normals=${2:-50}
patients=${3:-10}
seed=${4:-1}
cores=${CORES:-2}
build=$(cd "${BUILD_DIR:-build}" && pwd)
mkdir -p "$out"
more_features=${MORE_FEATURES:-"{t1w: anat/T1w}"}
out=$(cd "$out" && pwd)
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$build/pocl-cache}"
SECONDS=0
if [[ ! -f $out/bids/participants.tsv ]]; then
  /usr/bin/python3 scripts/synth_cohort.py --out "$out/bids" --normals "$normals" --patients "$patients" \
    --seed "$seed" --jobs "$cores" ${FOCI_FREE:+--foci-free "$FOCI_FREE"} ${REDUCTION:+--reduction "$REDUCTION"} \
    ${AGE_EFFECT:+--age-effect "$AGE_EFFECT"} ${SEX_EFFECT:+--sex-effect "$SEX_EFFECT"} \
    ${FWHM:+--fwhm "$FWHM"} ${NOISE_FWHM:+--noise-fwhm "$NOISE_FWHM"} ${CORTICAL:+--cortical} \
    ${FOCI_PER_PATIENT:+--foci-per-patient "$FOCI_PER_PATIENT"}
fi
synth_s=$SECONDS
snakemake -s workflow/Snakefile --cores "$cores" --directory "$out" \
  --config bids="$out/bids" out="$out/results" "more_features=$more_features" vpm="$build/vpm" \
  ${REGISTER:+"register=$REGISTER"} ${MESH:+"mesh=$MESH"}
workflow_s=$((SECONDS - synth_s))
peer_s=
if command -v elastix >/dev/null && command -v transformix >/dev/null; then
  /usr/bin/python3 bench/cohort/voxelwise_elastix.py --bids "$out/bids" --results "$out/results" --jobs "$cores" \
    ${PEER_SETTINGS:+--settings "$PEER_SETTINGS"}
  peer_s=$((SECONDS - synth_s - workflow_s))
else
  echo "run.sh: elastix or transformix not on PATH: the individual analysis is the affine baseline" >&2
fi
/usr/bin/python3 bench/cohort/summary.py --results "$out/results" --synth-seconds "$synth_s" \
  --workflow-seconds "$workflow_s" --cores "$cores" ${peer_s:+--peer-seconds "$peer_s"} \
  --out-json "$out/summary.json" --out-md "$out/summary.md"
cat "$out/summary.md"
