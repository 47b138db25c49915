#!/usr/bin/env bash
# End-to-end check of the cohort workflow (workflow/Snakefile) on a tiny synthetic cohort:
# 3 normals + 1 patient from scripts/synth_cohort.py, run to the group level with the
# evaluation against the planted truth; then a rerun must do nothing, a changed PET image must
# redo only that subject's sampling and the comparison, a subject whose files are deleted must be
# remade for the page, and a broken participants.tsv must stop the workflow with one line naming
# the file. (The workflow on Slurm: tests/workflow/slurm.sh.)
# Usage: cohort.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1
build=$2
work=$build/test-cohort
rm -rf "$work"
mkdir -p "$work"
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$build/pocl-cache}
fail() { echo "FAIL: $*" >&2; exit 1; }
# the mechanics are checked with workflow/fast.yaml (level-5 elements, 7.7x lighter than the
# default level 6, which the last check below runs) and brains of about 8,000 vertices (at the
# default 45,000 the whole check takes 1.6 times the CPU; the elements and the group level do
# not depend on the mesh's size)
printf 'mesh: {target_vertices: 8000}\n' > "$work/small_meshes.yaml"
fast=(--configfile "$src/workflow/fast.yaml" "$work/small_meshes.yaml")
smk() { (cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 2 "${fast[@]}" \
          --config bids="$work/bids" out="$work/results" vpm="$build/vpm" "$@"); }

/usr/bin/python3 "$src/scripts/synth_cohort.py" --out "$work/bids" --normals 3 --patients 1 --seed 11 --jobs 2
[[ $(head -1 "$work/bids/participants.tsv") == $'participant_id\tgroup\tseed\tfoci\tage\tsex' ]] ||
  fail "participants.tsv: not the foci, age and sex columns"
awk -F'\t' 'NR > 1 && !($5 >= 20 && $5 <= 80 && ($6 == "F" || $6 == "M")) { bad = 1 } END { exit bad }' \
  "$work/bids/participants.tsv" || fail "participants.tsv: an age outside 20-80 or a sex not F/M"
# the harder cohorts' options (issue 35) refuse what makes no sense, with exit 2 and one line, before any work
for bad in "--foci-free 2" "--foci-free -1" "--reduction 0.3,0.2" "--reduction 0,0.2" "--reduction 0.2" \
           "--age-effect 0.15" "--age-effect -0.01" "--sex-effect 0.3" "--sex-effect -0.3"; do
  rc=0
  /usr/bin/python3 "$src/scripts/synth_cohort.py" --out "$work/refused" --normals 3 --patients 1 $bad 2> "$work/refused.log" || rc=$?
  [[ $rc -eq 2 && $(wc -l < "$work/refused.log") -eq 1 && ! -e $work/refused ]] ||
    { cat "$work/refused.log"; fail "synth_cohort.py $bad: exit $rc, not a one-line refusal"; }
done
smk > "$work/run1.log" 2>&1 || { tail -40 "$work/run1.log"; fail "the workflow failed"; }
r=$work/results
for f in tables/sub-N01_pet.h5 tables/sub-P01_pet.h5 reference/pet.h5 compare/sub-P01_pet.tsv \
         compare/sub-P01_pet.json compare/sub-P01_pet_z.nii.gz compare/sub-P01_pet_foci.nii.gz view/cohort.html \
         compare/sub-P01_pet_native.vtu evaluation.json evaluation.md subjects/sub-P01/sub-P01_registered.vtu; do
  [[ -s $r/$f ]] || fail "missing $r/$f"
done
# the tables hold fast.yaml's element set (graded, level 5: 283,060 elements) with the T1w beside
# the PET (the default image covariate), and the comparison read 3 normals with the default
# hysteresis, relative extent and image covariate
# (HDF5, read here by h5py as any Python user would)
elements() { /usr/bin/python3 -c 'import h5py, sys; f = h5py.File(sys.argv[1], "r"); print(f["features/pet/mean"].shape[0], f["features/t1w/mean"].dtype)' "$1"; }
[[ $(elements "$r/tables/sub-N01_pet.h5") == "283060 float32" ]] || fail "sub-N01_pet.h5: not 283060 float32 PET and T1w values"
/usr/bin/python3 - "$r" <<'PY' || fail "reports"
import json, sys
r = sys.argv[1]
c = json.load(open(f"{r}/compare/sub-P01_pet.json"))
assert c["reference"]["subjects"] == 3, c["reference"]
assert c["definition"]["layout"] == "graded" and c["definition"]["shells"] == 41, c["definition"]
assert c["definition"]["level"] == 5 and c["definition"]["samples"] == 8, c["definition"]
assert c["options"]["extend"] == 2.25 and c["options"]["min_cluster"] == 60, c["options"]
assert c["reference"]["image_covariate"] == "t1w", c["reference"]
assert c["options"]["relative_extent"] == 0.3, c["options"]
reg = json.load(open(f"{r}/subjects/sub-P01/sub-P01_register.json"))
assert reg["input"]["landmarks"] >= 100, reg["input"]
# the default dense registration pulls by the T1w against the template's, then the image
# refinement lowers the mismatch further, the region centroids moving with it by little
d = reg["dense"]
assert d["force"] == "image" and d["mismatch_after"] < d["mismatch_landmarks"], {k: d.get(k) for k in ("force", "mismatch_landmarks", "mismatch_after")}
f = d["refine"]
assert f["iterations"] > 0 and f["mismatch_after"] < f["mismatch_before"], f
assert reg["landmark_rms_error"] < 0.05 and reg["inverted_tets"] == 0, reg["landmark_rms_error"]
e = json.load(open(f"{r}/evaluation.json"))
p = e["patients"][0]
assert p["participant_id"] == "sub-P01"
for m in ("vpm", "baseline"):
    assert 0 <= p[m]["sensitivity"] <= 1 and p[m]["foci_planted"] == 2, p[m]
    s = e["summary"][m]
    assert s["foci_free_patients"] == 0 and s["false_clusters_in_foci_free"] == 0, s
# the native foci table names each focus's main AAL region (view.label_names); no calibration
# with 3 normals, so no family-wise p-value
import csv
names = dict(l.split()[:2] for l in open("/usr/share/mricron/templates/aal.nii.txt") if l.strip())
rows = list(csv.DictReader(open(f"{r}/compare/sub-P01_pet_foci.tsv"), delimiter="\t"))
assert len(rows) == len(c["result"]["clusters"]) > 0, len(rows)
assert all(x["p_family"] == "NA" and x["region"] == names.get(x["label"], "") for x in rows), rows
assert any(x["region"] for x in rows), rows
PY
# leave-one-normal-out (bench/cohort/lono.py) with the patient counted among the "normals":
# its entry is a comparison against the three normals with the workflow's options, so it finds
# exactly the foci the workflow's comparison found
/usr/bin/python3 "$src/bench/cohort/lono.py" --results "$r" --normals-glob 'sub-*' --vpm "$build/vpm" \
  --out-json "$work/lono.json" > "$work/lono.log" 2>&1 || { cat "$work/lono.log"; fail "lono.py failed"; }
# with --calibrate it runs vpm calibrate (every min_cluster's count from one pass at min_cluster 1):
# at the workflow's own min_cluster that must count what the direct comparisons counted
/usr/bin/python3 "$src/bench/cohort/lono.py" --results "$r" --normals-glob 'sub-*' --vpm "$build/vpm" --calibrate 1 \
  --out-json "$work/lono_calibrated.json" > "$work/lono.log" 2>&1 || { cat "$work/lono.log"; fail "lono.py --calibrate failed"; }
/usr/bin/python3 - "$r" "$work/lono.json" "$work/lono_calibrated.json" <<'PY' || fail "leave-one-normal-out"
import json, sys
c = json.load(open(f"{sys.argv[1]}/compare/sub-P01_pet.json"))
l = json.load(open(sys.argv[2]))
k = json.load(open(sys.argv[3]))
assert [r["clusters"] for r in k["per_normal"]] == [r["clusters"] for r in l["per_normal"]], (k["per_normal"], l["per_normal"])
curve = k["calibration"]["curve"]
assert [p["false_clusters"] for p in curve] == sorted((p["false_clusters"] for p in curve), reverse=True), curve
at60 = [p["false_clusters"] for p in curve if p["min_cluster"] == 60]  # past the largest cluster: 0
assert (at60[0] if at60 else 0) == l["false_clusters"] and curve[-1]["false_clusters"] == 0, curve
rows = {row["normal"]: row for row in l["per_normal"]}
assert l["normals"] == 4 and len(rows) == 4, l
assert rows["sub-P01_pet.h5"]["clusters"] == len(c["result"]["clusters"]), (rows["sub-P01_pet.h5"], c["result"])
assert "--extend" in l["options"] and "--relative-extent" in l["options"] and l["options"][l["options"].index("--min-cluster") + 1] == "60", l["options"]
assert l["options"][l["options"].index("--image-covariate") + 1] == "t1w", l["options"]
assert abs(l["per_10_normals"] - 10 * l["false_clusters"] / 4) < 1e-12, l
PY
# compare.min_cluster: auto (the default; vpm calibrate in the workflow) needs 4 normals: with 3
# the workflow said so and used compare.fixed_min_cluster (60, checked in the sidecar above)
grep -q "compare.min_cluster: auto calibrates on at least 4 normals (each left out in turn), got 3: clusters of at least compare.fixed_min_cluster = 60 elements" "$work/run1.log" ||
  { tail -40 "$work/run1.log"; fail "min_cluster auto with 3 normals: no note of the fixed size"; }
# with 4 normals it calibrates: sub-N04, a copy of sub-N01 (images and registered meshes, mtimes
# kept), joins them; only the group level runs (its table sampled, the calibration, the comparison)
cp -a "$work/bids" "$work/four_bids"
cp -a "$work/results" "$work/four_results"
rm -rf "$work/four_results/compare" "$work/four_results/view" "$work/four_results/evaluation."*
for f in $(cd "$work/bids" && find sub-N01 -type f); do
  mkdir -p "$(dirname "$work/four_bids/${f//sub-N01/sub-N04}")"
  cp -a "$work/bids/$f" "$work/four_bids/${f//sub-N01/sub-N04}"
done
mkdir -p "$work/four_results/subjects/sub-N04"
for f in "$work"/results/subjects/sub-N01/*; do cp -a "$f" "$work/four_results/subjects/sub-N04/$(basename "${f//sub-N01/sub-N04}")"; done
awk -F'\t' -v OFS='\t' '{ print } $1 == "sub-N01" { $1 = "sub-N04"; print }' "$work/bids/participants.tsv" > "$work/four_bids/participants.tsv"
(cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 2 "${fast[@]}" --config bids="$work/four_bids" out="$work/four_results" \
   vpm="$build/vpm") > "$work/four.log" 2>&1 || { tail -40 "$work/four.log"; fail "the 4-normal group level failed"; }
jobs=$(awk '/^Job stats:/{s=1;next} s&&/^total/{exit} s&&NF==4&&$2~/^[0-9]+$/{print $1}' "$work/four.log" | sort | tr '\n' ' ')
[[ $jobs == "calibrate compare evaluate group normals_list reference reference_group sample view " ]] ||
  { cat "$work/four.log"; fail "4-normal run jobs: $jobs"; }
/usr/bin/python3 - "$work/four_results" <<'PY' || fail "calibrated min_cluster"
import json, sys
r = sys.argv[1]
cal = json.load(open(f"{r}/compare/calibration_pet.json"))
c = json.load(open(f"{r}/compare/sub-P01_pet.json"))
assert cal["normals"] == 4 and cal["image_covariate"] == "t1w" and cal["rate"] == 1, {k: cal[k] for k in ("normals", "image_covariate", "rate")}
assert cal["min_cluster"] >= 1 and c["options"]["min_cluster"] == cal["min_cluster"], (cal["min_cluster"], c["options"])
# compare.peak: auto (the default): the peak level calibrated beside the size and applied
assert cal["calibrate_peak"] is True and cal["options"]["peak"] == 0 and cal["peak"] >= 3, {k: cal[k] for k in ("calibrate_peak", "peak")}
assert c["options"]["peak"] == cal["peak"], (c["options"], cal["peak"])
assert c["reference"]["subjects"] == 4 and c["reference"]["image_covariate"] == "t1w", c["reference"]
# each normal's largest and strongest cluster: the null of the foci's family-wise p-values
assert all(n["largest"] >= 0 and n["strongest"] >= 0 for n in cal["per_normal"]), cal["per_normal"]
assert all(0.2 <= f["p_family"] <= 1 for f in c["result"]["clusters"]), c["result"]["clusters"]
PY
# compare.peak: neither auto nor a level stops the workflow before any job
if smk 'compare={peak: high}' -n > "$work/peak.log" 2>&1; then fail "compare.peak: a word ran"; fi
grep -q "compare.peak: 'high' is neither auto nor a |z| level >= 0" "$work/peak.log" ||
  { cat "$work/peak.log"; fail "compare.peak: no clear refusal"; }
# compare.detection: tfce calibrates its TFCE level (vpm calibrate --tfce, no peak rule), so it
# needs 4 normals (this cohort has 3) and refuses another word; with the 4-normal cohort the
# calibration and the comparisons are planned with it
if smk 'compare={detection: tfce}' -n > "$work/tfce.log" 2>&1; then fail "detection tfce ran with 3 normals"; fi
grep -q "compare.detection: tfce calibrates its level on the normals" "$work/tfce.log" ||
  { cat "$work/tfce.log"; fail "detection tfce: no clear refusal with 3 normals"; }
if smk 'compare={detection: blobs}' -n > "$work/tfce.log" 2>&1; then fail "detection: a word ran"; fi
grep -q "compare.detection: 'blobs' is neither clusters nor tfce" "$work/tfce.log" ||
  { cat "$work/tfce.log"; fail "detection: no clear refusal of a word"; }
(cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 2 "${fast[@]}" --config bids="$work/four_bids" \
   out="$work/four_results" vpm="$build/vpm" 'compare={detection: tfce}' --forcerun calibrate -n -p) > "$work/tfce.log" 2>&1 ||
  { tail -40 "$work/tfce.log"; fail "detection tfce: the 4-normal plan failed"; }
grep -qE "vpm\S* calibrate .*--tfce" "$work/tfce.log" && grep -qE "vpm\S* compare .*--min-cluster-from" "$work/tfce.log" ||
  { cat "$work/tfce.log"; fail "detection tfce: the calibration and comparisons are not planned with --tfce"; }
if grep -E "vpm\S* (calibrate|compare) " "$work/tfce.log" | grep -q -- "--peak"; then
  cat "$work/tfce.log"; fail "detection tfce: a peak rule is planned beside TFCE"
fi
# compare.covariates: a column the participants table lacks stops the workflow before any job,
# naming the table and the line; with columns it has, the comparisons are planned again with
# them (quoted, one word each)
if smk 'compare={covariates: [weight]}' -n > "$work/cov.log" 2>&1; then fail "covariates: an unknown column ran"; fi
grep -q "participants.tsv:1: no column 'weight' (compare.covariates)" "$work/cov.log" ||
  { cat "$work/cov.log"; fail "covariates: no clear refusal of an unknown column"; }
smk 'compare={covariates: [age, sex]}' -n -p > "$work/cov.log" 2>&1 || { cat "$work/cov.log"; fail "covariates: dry run"; }
grep -q -- "--covariates age,sex --participants $work/bids/participants.tsv" "$work/cov.log" ||
  { cat "$work/cov.log"; fail "covariates: not passed to vpm compare"; }
# a rerun does nothing
smk -n > "$work/run2.log" 2>&1
grep -q "Nothing to be done" "$work/run2.log" || { cat "$work/run2.log"; fail "a rerun would redo work"; }
# a newer PET image of one normal redoes its sampling and what depends on it, nothing else
sleep 1
touch "$work/bids/sub-N02/pet/sub-N02_pet.nii.gz"
smk -n > "$work/run3.log" 2>&1
jobs=$(awk '/^Job stats:/{s=1;next} s&&/^total/{exit} s&&NF==4&&$2~/^[0-9]+$/{print $1}' "$work/run3.log" | sort | tr '\n' ' ')
[[ $jobs == "compare evaluate group reference reference_group sample view " ]] || { cat "$work/run3.log"; fail "stale rerun plans: $jobs"; }
# a subject whose files are deleted is remade (the page's rule names every subject's table and
# registered mesh), beside the stale sampling above
rm -rf "$work/results/subjects/sub-N03"
smk > "$work/stale.log" 2>&1 || { tail -40 "$work/stale.log"; fail "the rerun of what is stale failed"; }
[[ -s $r/subjects/sub-N03/sub-N03_registered.vtu ]] || fail "the rerun did not remake sub-N03"
[[ $r/tables/sub-N02_pet.h5 -nt $work/bids/sub-N02/pet/sub-N02_pet.nii.gz ]] || fail "sub-N02's table not resampled"
smk -n > "$work/run4.log" 2>&1
grep -q "Nothing to be done" "$work/run4.log" || { cat "$work/run4.log"; fail "after the stale rerun a rerun would redo work"; }
# a changed truth mask (read by the evaluation, not by the analysis) redoes the evaluation only
# (new bytes: Snakemake skips small inputs whose checksum it recorded and that only got newer)
sleep 1
/usr/bin/python3 -c 'import gzip, sys; p = sys.argv[1]; d = gzip.open(p).read(); gzip.open(p, "wb", compresslevel=1).write(d)' \
  "$work/bids/derivatives/truth/sub-P01_foci.nii.gz"
smk -n > "$work/run5.log" 2>&1
jobs=$(awk '/^Job stats:/{s=1;next} s&&/^total/{exit} s&&NF==4&&$2~/^[0-9]+$/{print $1}' "$work/run5.log" | sort | tr '\n' ' ')
[[ $jobs == "evaluate group " ]] || { cat "$work/run5.log"; fail "a new truth mask plans: $jobs"; }
# a participants.tsv without a group column is refused naming the file
cp -r "$work/bids" "$work/bad"
printf 'participant_id\tage\nsub-N01\t30\n' > "$work/bad/participants.tsv"
if (cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 1 -n --config bids="$work/bad" out="$work/bad_results" \
      vpm="$build/vpm") > "$work/bad.log" 2>&1; then
  fail "a participants.tsv without group was accepted"
fi
grep -q "participants.tsv:1: needs a 'group' column" "$work/bad.log" || { cat "$work/bad.log"; fail "no clear error"; }
# a subject given by a brain mask instead of a T1w is registered by the region boundaries alone
cp -r "$work/bids" "$work/masked"
for f in "$work"/masked/sub-N01/anat/sub-N01_T1w.nii*; do mv "$f" "${f/_T1w/_mask}"; done
(cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 1 -n -p --config bids="$work/masked" \
   out="$work/masked_results" vpm="$build/vpm") > "$work/masked.log" 2>&1 || { tail -30 "$work/masked.log"; fail "masked plan"; }
grep -q "register .*sub-N01_ball.vtu" "$work/masked.log" || fail "no register job planned for the mask subject"
grep "register .*sub-N01_ball.vtu" "$work/masked.log" | grep -q -- "--dense-force" && fail "a mask subject got the image force"
grep "register .*sub-N02_ball.vtu" "$work/masked.log" | grep -q -- "--dense-force image --image" ||
  { grep "register" "$work/masked.log"; fail "a T1w subject lost the image force"; }
# ... and with one subject without a T1w, compare.image_covariate: auto models none
grep -q "compare .*--feature" "$work/masked.log" || fail "no compare job planned for the masked cohort"
grep "compare .*--feature" "$work/masked.log" | grep -q -- "--image-covariate" && fail "image covariate with a mask subject"
# compare.image_covariate: t1w asked for outright is refused there, naming the subject
if (cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 1 -n --config bids="$work/masked" \
      out="$work/masked_results" vpm="$build/vpm" 'compare={image_covariate: t1w}') > "$work/masked2.log" 2>&1; then
  fail "image_covariate t1w accepted with a mask subject"
fi
grep -q "compare.image_covariate: t1w: sub-N01 has no such image" "$work/masked2.log" || { cat "$work/masked2.log"; fail "no clear error"; }
# a page drawn a level coarser than the tables names both levels and keeps the foci's elements' worth
"$build/vpm" view "$r" --display-level 4 --data file -o "$work/page4.html" > "$work/page4.log" 2>&1 ||
  { cat "$work/page4.log"; fail "vpm view --display-level 4"; }
/usr/bin/python3 - "$work/page4.html" <<'PY' || fail "the level-4 page's manifest"
import json, sys
page = open(sys.argv[1], encoding="utf-8").read()
m = json.loads(page.split('<script id="vpm-manifest" type="application/json">')[1].split("</script>")[0])
assert m["definition"]["level"] == 4 and m["compared"]["level"] == 5, (m["definition"], m.get("compared"))
assert m["compared"]["elements"] == 283060 and m["elements"] < 283060 / 4, m["elements"]  # fast.yaml: level 5
PY
# the defaults: level-6 elements (2,167,220), foci drawn to 0.22 of their peak deficit, the page
# drawn at level 5, and rules that ask for the memory level-6 tables take; run on the same
# registered meshes (the group level and the sampling only)
d=$work/default_results
mkdir -p "$d"
cp -a "$r/subjects" "$r/template" "$d/"
(cd "$work" && snakemake -s "$src/workflow/Snakefile" --cores 2 -p --config bids="$work/bids" out="$d" \
   vpm="$build/vpm") > "$work/default.log" 2>&1 || { tail -40 "$work/default.log"; fail "the workflow at its defaults"; }
[[ $(elements "$d/tables/sub-N01_pet.h5") == "2167220 float32" ]] || fail "sub-N01_pet.h5: not the 2,167,220 level-6 elements"
grep "compare .*--feature" "$work/default.log" | grep -q -- "--relative-extent 0.22 .*--min-cluster 460" ||
  { grep "compare .*--feature" "$work/default.log"; fail "the defaults' comparison options"; }
/usr/bin/python3 - "$work/default.log" "$d" <<'PY' || fail "the defaults' memory, page or foci"
import json, re, sys
mem, rule = {}, None
for line in open(sys.argv[1]):
    m = re.match(r"(?:local)?rule (\w+):", line.strip())
    rule = m.group(1) if m else rule
    m = re.search(r"resources: .*mem_mb=(\d+)", line)
    if m and rule:
        mem.setdefault(rule, int(m.group(1)))
# the group level's memory follows the element level, not the normals (level 5 asks about 1,100
# MB to sum, compare or draw this small cohort); sampling holds no table of samples (1,000)
assert mem.get("sample", 0) == 1000 and mem.get("compare", 0) >= 1800 and mem.get("reference_group", 0) >= 1800, mem
# the page holds a subject's display arrays, not its table (level 6: 154 MB a table), and asks for
# more than it took here
assert 1300 <= mem.get("view", 0) < 1000 + 4 * 154, mem
view_rss = float(open(f"{sys.argv[2]}/benchmarks/view.tsv").read().split("\n")[1].split("\t")[2])
assert view_rss < mem["view"], (view_rss, mem["view"])
page = open(f"{sys.argv[2]}/view/cohort.html", encoding="utf-8").read()
m = json.loads(page.split('<script id="vpm-manifest" type="application/json">')[1].split("</script>")[0])
assert m["definition"]["level"] == 5 and m["compared"]["level"] == 6 and m["elements"] == 283060, m["definition"]
s = json.load(open(f"{sys.argv[2]}/evaluation.json"))["summary"]["vpm"]
assert 0 <= s["pooled"]["dice"] <= 1 and s["foci_planted"] == 2, s
print(f"defaults: {s['foci_found']}/{s['foci_planted']} foci, Dice {s['pooled']['dice']:.3f}, {s['false_positive_clusters']} false")
PY
echo "cohort workflow: ok"
