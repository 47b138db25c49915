#!/usr/bin/env bash
# The cohort workflow on a dataset it must not trust (workflow/dataset.py, docs/robustness.md).
# 1. A real run, to the group level, of the synthetic cohort of tests/workflow/cohort.sh renamed
#    with hostile but legal names (shell substitutions, backticks, semicolons, quotes, spaces,
#    unicode, a 240-byte name, a dataset folder and an output folder with '$(...)' and spaces,
#    a symbolic link inside the dataset): it must finish, and nothing in any name may have run
#    (the names create files called pwned* when a shell executes them).
# 2. Datasets the workflow refuses, each with one line naming the file (and nothing run): braces,
#    a newline, a comma, a symbolic link out of the dataset, a bad participant id, a bad group,
#    a duplicate id.
# Usage: hostile.sh SOURCE_DIR BUILD_DIR   (needs the fixture of workflow:cohort: BUILD/test-cohort/bids)
set -euo pipefail
src=$1
build=$2
fixture=$build/test-cohort/bids
[[ -f $fixture/participants.tsv ]] || { echo "FAIL: no $fixture (run workflow:cohort first)" >&2; exit 1; }
work=$build/test-hostile
rm -rf "$work"
mkdir -p "$work/run dir"
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$build/pocl-cache}
fail() { echo "FAIL: $*" >&2; exit 1; }

bids='$(touch pwned-root) bids `touch pwned-tick` dir'
ds=$work/$bids
cp -r "$fixture" "$ds"
rm -rf "$ds/derivatives"  # no planted truth: the evaluation (a bench script) does not run here
long=$(printf 'x%.0s' $(seq 1 215))
mv "$ds/sub-N01/anat/sub-N01_T1w.nii.gz" "$ds/sub-N01/anat/sub-N01_acq-\$(touch pwned1);touch pwned2_T1w.nii.gz"
mv "$ds/sub-N02/anat/sub-N02_dseg.nii.gz" "$ds/sub-N02/anat/sub-N02_desc-it's \"my\" atlas_dseg.nii.gz"
mv "$ds/sub-N03/pet/sub-N03_pet.nii.gz" "$ds/sub-N03/pet/sub-N03_acq-é中 \`touch pwned3\`_pet.nii.gz"
mv "$ds/sub-P01/pet/sub-P01_pet.nii.gz" "$ds/sub-P01/pet/sub-P01_acq-${long}_pet.nii.gz"
# a link that stays inside the dataset is fine
mkdir -p "$ds/sourcedata"
mv "$ds/sub-P01/anat/sub-P01_T1w.nii.gz" "$ds/sourcedata/P01 T1w.nii.gz"
ln -s "../../sourcedata/P01 T1w.nii.gz" "$ds/sub-P01/anat/sub-P01_T1w.nii.gz"

# a small, quick configuration: 1,500-vertex meshes, 2 dense iterations, level-5 elements, no page
cat > "$work/config.yaml" <<'YAML'
mesh: {target_vertices: 1500}
register: {extra: "--dense-iterations 2", force: both}
elements: {level: 5}
compare: {fixed_min_cluster: 60}
view: {enabled: false}
YAML
out='$(touch pwned-out) results'
smk() { (cd "$work/run dir" && snakemake -s "$src/workflow/Snakefile" --cores 2 --configfile "$work/config.yaml" \
           --config bids="$1" out="$out" vpm="$build/vpm" "${@:2}"); }
smk "$ds" -p > "$work/run.log" 2>&1 || { tail -40 "$work/run.log"; fail "the workflow failed on hostile names"; }
pwned=$(find "$work" -name 'pwned*' 2>/dev/null || true)
[[ -z $pwned ]] || fail "a dataset name was executed: $pwned"
r="$work/run dir/$out"
for f in tables/sub-N01_pet.h5 tables/sub-N03_pet.h5 compare/sub-P01_pet.tsv compare/sub-P01_pet_foci.nii.gz \
         subjects/sub-N02/sub-N02_registered.vtu; do
  [[ -s $r/$f ]] || fail "missing $r/$f"
done
# the hostile file names reached vpm whole: the T1w of sub-N01 was read by the dense image force
grep -q "register .*--image '.*sub-N01_acq-\$(touch pwned1);touch pwned2_T1w.nii.gz'" "$work/run.log" ||
  { grep register "$work/run.log"; fail "the printed register command of sub-N01 is not quoted"; }

# refused datasets: a dry run stops before any job with one line naming the file
refuse() {  # refuse NAME EXPECTED-TEXT: runs the workflow on $work/bad and expects the message
  if smk "$work/bad" -n > "$work/refuse-$1.log" 2>&1; then fail "$1: the dataset was accepted"; fi
  grep -qF -- "$2" "$work/refuse-$1.log" || { cat "$work/refuse-$1.log"; fail "$1: no clear message"; }
  ! grep -q "^rule " "$work/refuse-$1.log" || fail "$1: jobs were planned"
  rm -rf "$work/bad"
}
fresh() { cp -r "$fixture" "$work/bad"; rm -rf "$work/bad/derivatives"; }
fresh; mv "$work/bad/sub-N02/anat/sub-N02_T1w.nii.gz" "$work/bad/sub-N02/anat/sub-N02_acq-\${HOME}_T1w.nii.gz"
refuse braces "sub-N02_acq-\${HOME}_T1w.nii.gz': T1w image: the name holds '{'"
fresh; mv "$work/bad/sub-N02/pet/sub-N02_pet.nii.gz" "$work/bad/sub-N02/pet/sub-N02_acq-a"$'\n'"b_pet.nii.gz"
refuse newline "sub-N02_acq-a\\nb_pet.nii.gz': pet image: the name holds '\\n'"
fresh; mv "$work/bad/sub-N03/pet/sub-N03_pet.nii.gz" "$work/bad/sub-N03/pet/sub-N03_acq-a,b_pet.nii.gz"
refuse comma "sub-N03_acq-a,b_pet.nii.gz': pet image: the name holds ','"
fresh; rm "$work/bad/sub-N01/anat/sub-N01_dseg.nii.gz"; ln -s /etc/passwd "$work/bad/sub-N01/anat/sub-N01_dseg.nii.gz"
refuse symlink "sub-N01_dseg.nii.gz: atlas labels (_dseg): resolves to /etc/passwd, outside the dataset"
fresh; mv "$work/bad/sub-N01" "$work/outside"; ln -s "$work/outside" "$work/bad/sub-N01"
refuse folder-link "sub-N01: subject folder: resolves to $work/outside, outside the dataset"
rm -rf "$work/outside"
fresh; printf 'sub-N04;id\tnormal\n' >> "$work/bad/participants.tsv"
refuse id "participants.tsv:6: participant_id 'sub-N04;id' is not 'sub-' and 1-60 letters or digits"
fresh; sed -i 's/^sub-N03\tnormal/sub-N03\t$(id)/' "$work/bad/participants.tsv"
refuse group "participants.tsv:4: group '\$(id)' of sub-N03 is not 1-64 letters"
fresh; sed -n 2p "$work/bad/participants.tsv" >> "$work/bad/participants.tsv"
refuse duplicate "participants.tsv:6: participant_id sub-N01 appears twice"
pwned=$(find "$work" -name 'pwned*' 2>/dev/null || true)
[[ -z $pwned ]] || fail "a dataset name was executed: $pwned"
echo "hostile dataset: ok"
