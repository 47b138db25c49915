#!/usr/bin/env bash
# A cohort killed mid-run and resumed equals one that ran uninterrupted (docs/robustness.md).
# The synthetic cohort of tests/workflow/cohort.sh, with a small configuration, runs once
# through; a second run is killed with SIGKILL (its whole process group, as a scheduler kills a
# job) while jobs are writing, then resumed as docs/cohort.md says (--unlock, then --rerun-incomplete). No output may be
# partial at any point, and every result of the resumed run (tables, comparisons, z-maps, foci
# masks and tables, meshes) must equal the uninterrupted run's byte for byte.
# Usage: resume.sh SOURCE_DIR BUILD_DIR   (needs the fixture of workflow:cohort: BUILD/test-cohort/bids)
set -euo pipefail
src=$1
build=$2
bids=$build/test-cohort/bids
[[ -f $bids/participants.tsv ]] || { echo "FAIL: no $bids (run workflow:cohort first)" >&2; exit 1; }
work=$build/test-resume
rm -rf "$work"
mkdir -p "$work"
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$build/pocl-cache}
fail() { echo "FAIL: $*" >&2; exit 1; }
cat > "$work/config.yaml" <<'YAML'
mesh: {target_vertices: 1500}
register: {extra: "--dense-iterations 2", force: both}
elements: {level: 5}
compare: {fixed_min_cluster: 60}
view: {enabled: false}
YAML
smk() {  # smk OUT [snakemake options...]
  (cd "$work" && exec snakemake -s "$src/workflow/Snakefile" --cores 2 --configfile "$work/config.yaml" \
     --config bids="$bids" out="$1" vpm="$build/vpm" "${@:2}")
}
# results a run must produce (reports, logs and benchmarks hold times and are left out)
results() {
  (cd "$1" && find . -type f \( -name '*.tsv' -o -name '*.h5' -o -name '*.nii.gz' -o -name '*.vtu' \) \
     ! -path './benchmarks/*' ! -path './logs/*' | sort)
}

smk "$work/straight" > "$work/straight.log" 2>&1 || { tail -30 "$work/straight.log"; fail "the uninterrupted run failed"; }

# the second run, killed when its first registration has started (a job in flight), in its own
# process group so that every job dies with it
(cd "$work" && setsid snakemake -s "$src/workflow/Snakefile" --cores 2 --configfile "$work/config.yaml" \
   --config bids="$bids" out="$work/killed" vpm="$build/vpm" > "$work/killed.log" 2>&1) &
runner=$!
for _ in $(seq 1 600); do
  compgen -G "$work/killed/logs/*_register.log" > /dev/null && break
  kill -0 "$runner" 2>/dev/null || break
  sleep 0.1
done
pgid=$(ps -o pgid= -p "$(pgrep -n -f "out=$work/killed")" 2>/dev/null | tr -d ' ' || true)
[[ -n $pgid ]] || fail "the run to kill had already ended (see $work/killed.log)"
kill -KILL -- "-$pgid"
wait "$runner" 2>/dev/null || true
sleep 0.5
# nothing half-written: no vpm temporary files, and every result present is complete
left=$(find "$work/killed" -name '.*.tmp.*' 2>/dev/null || true)
[[ -z $left ]] || fail "temporary files left by the killed run: $left"
done_before=$(results "$work/killed" | wc -l)
total=$(results "$work/straight" | wc -l)
((done_before < total)) || fail "the kill came too late: $done_before of $total results were there"

# as a user resumes after a kill: release Snakemake's lock, rerun what was incomplete
smk "$work/killed" --unlock > "$work/unlock.log" 2>&1 || { cat "$work/unlock.log"; fail "--unlock failed"; }
smk "$work/killed" --rerun-incomplete > "$work/resumed.log" 2>&1 ||
  { tail -30 "$work/resumed.log"; fail "the resumed run failed"; }
diff <(results "$work/straight") <(results "$work/killed") > "$work/files.diff" ||
  { cat "$work/files.diff"; fail "the resumed run's results are not the same files"; }
# HDF5 files (tables, reference sums) name the paths they came from, which differ between the two
# output folders: their values are compared (every dataset, exactly), the names as file names
same_h5() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import json, os, sys
import h5py, numpy as np
a, b = (h5py.File(p, "r") for p in sys.argv[1:3])
def datasets(f):
    out = []
    f.visititems(lambda name, o: out.append(name) if isinstance(o, h5py.Dataset) else None)
    return sorted(out)
assert datasets(a) == datasets(b), (datasets(a), datasets(b))
for name in datasets(a):
    x, y = a[name][()], b[name][()]
    if name == "normals/names":
        x, y = ([os.path.basename(p) for p in json.loads(bytes(v).decode())] for v in (x, y))
    assert np.array_equal(x, y), name
PY
}
while read -r f; do
  if [[ $f == *.h5 ]]; then
    same_h5 "$work/straight/$f" "$work/killed/$f" || fail "$f differs between the uninterrupted and the resumed run"
  else
    cmp -s "$work/straight/$f" "$work/killed/$f" || fail "$f differs between the uninterrupted and the resumed run"
  fi
done < <(results "$work/straight")
echo "resume: killed with $done_before of $total results written; resumed results equal ($total files)"
