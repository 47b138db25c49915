#!/bin/bash
# usage: l6.sh NAME BIDS RESULTS  -- level-6 tables, calibration, variants 0.22/0.25/0.3
set -u
NAME=$1; B=$2; R=$3; V=/work/exp36/bin/vpm
export POCL_CACHE_DIR=/work/runs/pocl-cache
T=/work/exp37/$NAME/t6; mkdir -p $T
cd /work/exp37/$NAME
start=$(date +%s)
ls $R/subjects | xargs -P2 -I{} sh -c "test -s $T/{}_pet.tsv || $V sample $R/subjects/{}/{}_registered.vtu -o $T/{}_pet.tsv --images pet=$B/{}/pet/{}_pet.nii.gz,t1w=$B/{}/anat/{}_T1w.nii.gz --subject {} --level 6 --layout graded --samples 8 --quiet"
echo "sample $(( $(date +%s) - start )) s" > times.txt
N=$(ls $T/sub-N*_pet.tsv | paste -sd, -)
/usr/bin/time -f "%e s %M KB" $V calibrate --normals "$N" --feature pet --normalisation proportional --smooth 0 --shrink 0.8 --test z --sign hypo --threshold 3 --extend 2.25 --relative-extent 0.22 --image-covariate t1w --rate 1 --peak auto -o pk6.json > cal6.log 2>&1
OPT="--normalisation proportional --smooth 0 --shrink 0.8 --min-cluster - --test z --sign hypo --threshold 3 --extend 2.25 --image-covariate t1w --min-cluster-from /work/exp37/$NAME/pk6.json"
s2=$(date +%s)
/usr/bin/python3 /work/main/bench/cohort/compare_variants.py --bids $B --results $R --out real6 --vpm $V \
  --tables z0.22 $T --tables z0.25 $T --tables z0.3 $T \
  --variant z0.22 "$OPT --relative-extent 0.22" --variant z0.25 "$OPT --relative-extent 0.25" --variant z0.3 "$OPT --relative-extent 0.3" --jobs 2 > real6.log 2>&1
echo "compare $(( $(date +%s) - s2 )) s" >> times.txt
echo done > done
