#!/usr/bin/env bash
# The cohort workflow on a real Slurm cluster: a one-node cluster on this machine
# (tests/workflow/slurm_cluster.sh: munged, slurmdbd over a private MariaDB, slurmctld, slurmd,
# all under BUILD/test-slurm/cluster, stopped by pid at exit) runs the workflow with
# workflow/profiles/slurm, filled in as a user would (account, partition; caps lowered to 1 CPU
# and 1,500 MB; 2 subjects a group job), on the cohort of the workflow:cohort fixture with a small
# configuration. Checked against the scheduler's own accounting (sacct):
#   * the participant-level rules go out as group jobs (2 for the 4 subjects, 16 rules), each
#     within the caps, charged to the account, in the partition, with the group's runtime, and
#     each rule run as a job step (srun);
#   * the first run is killed once a group job has finished its first subject (Snakemake
#     SIGKILLed, its jobs cancelled with scancel); the next invocation (--unlock, then the
#     profile's --rerun-incomplete) redoes only what had not finished: the results of the Slurm
#     jobs and job steps (a subject's chain in a group job) finished before the kill are kept as
#     they were (same bytes, same time), those of the cut-off subjects' finished rules (which
#     Snakemake removes when their step is cancelled) come back with the same bytes, every
#     expected result exists afterwards and a further run has nothing to do;
#   * in that second run one subject's `vpm sample` fails once: its group job FAILs in Slurm, the
#     profile's restart-times resubmits it and the workflow completes.
# Needs root and the packages of scripts/setup.sh; otherwise it fails in CI (CI=true) and
# skips (exit 77) elsewhere.
# Usage: slurm.sh SOURCE_DIR BUILD_DIR   (needs the fixture of workflow:cohort: BUILD/test-cohort/bids)
set -euo pipefail
src=$(realpath "$1")
build=$(realpath "$2")
fail() { echo "FAIL: $*" >&2; exit 1; }
cannot() {
  [[ ${CI:-} == true ]] && fail "cannot run the one-node Slurm cluster: $*"
  echo "SKIP: cannot run the one-node Slurm cluster: $*"
  exit 77
}
[[ $(id -u) -eq 0 ]] || cannot "not root (its daemons run as root)"
export PATH=$PATH:/usr/sbin:/sbin  # the daemons
for c in munged munge mariadb-install-db mariadbd slurmdbd slurmctld slurmd sbatch sacct sacctmgr scontrol sinfo squeue scancel; do
  command -v "$c" > /dev/null || cannot "no $c (bash scripts/setup.sh installs it)"
done
bids=$build/test-cohort/bids
[[ -f $bids/participants.tsv ]] || fail "no $bids (run workflow:cohort first)"
work=$build/test-slurm
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$build/pocl-cache}
export USER=${USER:-$(id -un)}  # Snakemake's Slurm executor needs it (clusters set it; some containers do not)
t0=$SECONDS
source "$src/tests/workflow/slurm_cluster.sh"
trap cluster_stop EXIT
trap 'exit 143' INT TERM
cluster_stop_stale "$work/cluster"
rm -rf "$work"
mkdir -p "$work"
cluster_start "$work/cluster" || fail "the one-node cluster did not start (logs in $work/cluster/log)"
echo "slurm: one-node cluster up in $((SECONDS - t0)) s ($CLUSTER_CPUS CPUs, $CLUSTER_MEM_MB MB)"

# the profile as a user fills it in, the caps lowered to fit the node; 2 subjects a group job
sed -e "s/YOUR_ACCOUNT/$CLUSTER_ACCOUNT/; s/YOUR_PARTITION/$CLUSTER_PARTITION/" \
    -e 's/^cores: 8$/cores: 1/; s/mem_mb=16000$/mem_mb=1500/; s/participant=25$/participant=2/' \
  "$src/workflow/profiles/slurm/config.yaml" > "$work/profile.yaml"
for want in "^cores: 1$" "mem_mb=1500$" "participant=2$" "slurm_account=$CLUSTER_ACCOUNT$" \
            "slurm_partition=$CLUSTER_PARTITION$" "^restart-times: [1-9]" "^rerun-incomplete: true$"; do
  grep -q -- "$want" "$work/profile.yaml" || fail "workflow/profiles/slurm/config.yaml: no line matching '$want' after filling it in"
done
mkdir -p "$work/profile"
mv "$work/profile.yaml" "$work/profile/config.yaml"
cat > "$work/config.yaml" <<'YAML'
mesh: {target_vertices: 1500}
register: {extra: "--dense-iterations 2", force: both}
elements: {level: 5}
compare: {fixed_min_cluster: 60}
view: {enabled: false}
YAML
# vpm, except that the first `vpm sample` of the subject named in fail_once fails (exit 3)
cat > "$work/vpm" <<EOF
#!/usr/bin/env bash
if [[ \${1-} == sample && -s $work/fail_once && " \$* " == *" --subject \$(cat $work/fail_once) "* ]] &&
   mkdir "$work/failed_once" 2> /dev/null; then
  echo "vpm: failure injected by tests/workflow/slurm.sh" >&2
  exit 3
fi
exec "$build/vpm" "\$@"
EOF
chmod +x "$work/vpm"
r=$work/results
conf=(--configfile "$work/config.yaml" --config bids="$bids" out="$r" vpm="$work/vpm")
on_slurm() { (cd "$work" && exec timeout --foreground 480 snakemake -s "$src/workflow/Snakefile" --profile "$work/profile" \
                --max-status-checks-per-second 1 "${conf[@]}" "$@"); }
local_smk() { (cd "$work" && exec snakemake -s "$src/workflow/Snakefile" --cores 1 "${conf[@]}" "$@"); }
subjects=$(awk -F'\t' 'NR > 1 { print $1 }' "$bids/participants.tsv")
# results (reports, logs and benchmarks hold times and are left out), with their times and sums
snapshot() {
  (cd "$r" && find . -type f \( -name '*.tsv' -o -name '*.h5' -o -name '*.nii.gz' -o -name '*.vtu' \) \
     ! -path './benchmarks/*' ! -path './logs/*' -printf '%P %T@\n' | sort |
   while read -r f t; do echo "$f $t $(sha256sum < "$f" | cut -c1-64)"; done)
}

# 1. the run killed mid-cohort: once a participant group job has finished its first subject (a
#    job step: Snakemake runs each subject's chain of a group job as one srun step), Snakemake is
#    SIGKILLed (its whole process group: it and its sbatch/sacct calls) and its jobs cancelled,
#    as a lost login session and `scancel -u $USER` leave them
set -m
on_slurm > "$work/killed.log" 2>&1 &
runner=$!
set +m
step_done() {
  sacct -S 2000-01-01 -n -P -o JobID,JobName,State 2>/dev/null | awk -F'|' '
    $1 !~ /[.]/ && $2 ~ /^snakejob_participant_/ { p[$1] = 1 }
    $1 ~ /^[0-9]+[.][0-9]+$/ && $3 == "COMPLETED" { split($1, a, "."); if (a[1] in p) found = 1 }
    END { exit !found }'
}
for _ in $(seq 1 600); do
  step_done && break
  kill -0 "$runner" 2>/dev/null || break
  sleep 0.5
done
kill -0 "$runner" 2>/dev/null || { tail -40 "$work/killed.log"; fail "the first run ended before a subject was done"; }
{ kill -KILL -- "-$runner"; wait "$runner"; } 2>/dev/null || true
squeue -h -o '%i %j %T' > "$work/queue_at_kill.txt"
grep -q 'snakejob_participant_.* RUNNING' "$work/queue_at_kill.txt" ||
  { cat "$work/queue_at_kill.txt"; fail "no participant group job running at the kill"; }
scancel -u "$USER"
for _ in $(seq 1 150); do [[ -z $(squeue -h -o %i) ]] && break; sleep 0.2; done
[[ -z $(squeue -h -o %i) ]] || { squeue; fail "jobs still in the queue 30 s after scancel"; }
# the results as the next invocation finds them, once every job has stopped (a group job that
# finishes between the kill and scancel touches its outputs as it ends: taken earlier, this
# snapshot would see that as a redone result)
snapshot > "$work/at_kill.txt"
echo "slurm: Snakemake killed $((SECONDS - t0)) s in, $(grep -c . "$work/at_kill.txt") results written, $(grep -c RUNNING "$work/queue_at_kill.txt") jobs running"
next_job() { scontrol show config | sed -n 's/^NEXT_JOB_ID *= *//p'; }
first_jobs=$(($(next_job) - 1))   # the jobs of the first run: 1 to this
left=$(find "$r" -name '.*.tmp.*' 2>/dev/null || true)
[[ -z $left ]] || fail "temporary files left by the cancelled jobs: $left"

# 2. the next invocation, as docs/cohort.md says: --unlock, then the profile (rerun-incomplete).
#    What it plans (dry run) is what had not finished; one subject among those fails its sampling once
on_slurm --unlock > "$work/unlock.log" 2>&1 || { cat "$work/unlock.log"; fail "--unlock failed"; }
local_smk -n --rerun-incomplete > "$work/plan.log" 2>&1 || { tail -30 "$work/plan.log"; fail "the dry run after the kill"; }
awk '/^ *output: /{ sub(/^ *output: /, ""); n = split($0, a, /, /); for (i = 1; i <= n; i++) print a[i] }' "$work/plan.log" |
  sed "s|^$r/||" | sort > "$work/planned.txt"
grep -q '^tables/' "$work/planned.txt" || { cat "$work/planned.txt"; fail "no sampling left after the kill"; }
# kept: the template's jobs and every subject whose job step had finished (its four results)
kept=$(cut -d' ' -f1 "$work/at_kill.txt" | grep -v -x -F -f "$work/planned.txt" || true)
grep -q '^template/template_ball.vtu$' <<< "$kept" && grep -q '^tables/' <<< "$kept" ||
  { cat "$work/at_kill.txt" "$work/planned.txt"; fail "the results of the jobs and steps finished before the kill were not all kept"; }
for t in $(grep '^tables/' <<< "$kept"); do
  s=$(basename "$t" | sed 's/_.*//')
  [[ $(grep -c "^subjects/$s/" <<< "$kept") -eq 3 ]] || { echo "$kept"; fail "$s was sampled before the kill but its meshes are planned again"; }
done
victim=$(sed -n 's|^tables/\(sub-[A-Za-z0-9]*\)_.*|\1|p' "$work/planned.txt" | head -1)
echo "$victim" > "$work/fail_once"
on_slurm > "$work/resumed.log" 2>&1 || { tail -60 "$work/resumed.log"; fail "the resumed run failed"; }
removed=$(cut -d' ' -f1 "$work/at_kill.txt" | grep -c -x -F -f "$work/planned.txt" || true)
echo "slurm: resumed run done $((SECONDS - t0)) s in: $(grep -c . <<< "$kept") results kept," \
  "$removed finished ones of the cancelled steps redone, $(grep -c . "$work/planned.txt") jobs in all; $victim's sampling failed once"

# every result there at the kill that was not planned again is untouched (bytes and time), and
# those redone have the same bytes
snapshot > "$work/after.txt"
while read -r f t h; do
  now=$(grep -F -- "$f " "$work/after.txt" | head -1) || fail "$f, written before the kill, is gone"
  [[ $(cut -d' ' -f3 <<< "$now") == "$h" ]] || fail "$f, written before the kill, changed"
  grep -q -x -F -- "$f" "$work/planned.txt" || [[ $(cut -d' ' -f2 <<< "$now") == "$t" ]] ||
    fail "$f had finished before the kill and was redone"
done < "$work/at_kill.txt"
for s in $subjects; do
  [[ -s $r/subjects/$s/${s}_registered.vtu ]] || fail "missing $s's registered mesh"
  compgen -G "$r/tables/${s}_pet.*" > /dev/null || fail "missing $s's table"
done
[[ -s $r/evaluation.json ]] && compgen -G "$r/compare/sub-P01_pet*" > /dev/null || fail "missing the comparison or the evaluation"
local_smk -n > "$work/rerun.log" 2>&1
grep -q "Nothing to be done" "$work/rerun.log" || { cat "$work/rerun.log"; fail "after the resumed run a rerun would redo work"; }
[[ -d $work/failed_once ]] || fail "the injected failure did not happen"
grep -q "Trying to restart job" "$work/resumed.log" || { tail -60 "$work/resumed.log"; fail "no restart of the failed job"; }

# what Slurm saw: every job of both runs, from its accounting (once slurmdbd has them all)
n=$(($(next_job) - 1))
for _ in $(seq 1 60); do
  [[ $(sacct -S 2000-01-01 -n -X -P -o JobID,State | awk -F'|' '$2 !~ /^(PENDING|RUNNING)$/' | wc -l) -eq $n ]] && break
  sleep 0.5
done
sacct -S 2000-01-01 -n -P -o JobID,JobName,Account,Partition,Timelimit,ReqMem,ReqCPUS,State > "$work/sacct.txt"
/usr/bin/python3 - "$work/sacct.txt" "$first_jobs" "$CLUSTER_ACCOUNT" "$CLUSTER_PARTITION" "$n" "$work/killed.log" "$work/resumed.log" <<'PY' ||
import collections, re, sys
rows = [l.rstrip("\n").split("|") for l in open(sys.argv[1])]
first, account, partition, n = int(sys.argv[2]), sys.argv[3], sys.argv[4], int(sys.argv[5])
jobs = {r[0]: dict(zip(("id", "name", "account", "partition", "time", "mem", "cpus", "state"), r)) for r in rows if "." not in r[0]}
assert sorted(map(int, jobs)) == list(range(1, n + 1)), (sorted(jobs), n)  # every job submitted is accounted for
steps = collections.Counter(r[0].split(".")[0] for r in rows if re.match(r"^\d+\.\d+$", r[0]))
kind = lambda j: re.sub(r"_[0-9a-f-]+$", "", j["name"])
minutes = lambda t: sum(int(x) * m for x, m in zip(reversed(re.split("[-:]", t)), (1 / 60, 1, 60, 1440)))
for j in jobs.values():
    assert j["account"] == account and j["partition"] == partition, j
    assert j["cpus"] == "1" and j["mem"].endswith("M") and 0 < int(j["mem"][:-1]) <= 1500, j  # within the caps
    assert minutes(j["time"]) > 0, j
# the time each job asks for is what Snakemake says its rules need: a group capped at 1 CPU runs
# its rules one after another, so the sum of their runtimes (two subjects: 2 x 35 minutes)
asked = {}  # Slurm job id: (minutes, rules)
for log in sys.argv[6:8]:
    block, printed = [], {}
    for line in open(log):
        m = re.search(r"runtime=(\d+)", line)
        if m:
            block.append(int(m.group(1)))
        m = re.match(r"Job (\S+) has been submitted with SLURM jobid (\d+)", line)
        if m:  # a job resubmitted (restart-times) is not printed again
            printed[m.group(1)] = (sum(block), len(block)) if block else printed[m.group(1)]
            asked[m.group(2)] = printed[m.group(1)]
            block = []
for j in jobs.values():
    assert minutes(j["time"]) == asked[j["id"]][0], (j, asked[j["id"]])
groups = [j for j in jobs.values() if kind(j) == "snakejob_participant"]
assert all(asked[j["id"]][1] == 8 for j in groups if int(j["id"]) <= first), asked  # 2 subjects x 4 rules
# the first run: the template's two jobs, then the 4 subjects' 16 rules as 2 group jobs
run1 = sorted(kind(j) for j in jobs.values() if int(j["id"]) <= first)
assert run1 == ["snakejob_participant"] * 2 + ["snakejob_template_map", "snakejob_template_mesh"], run1
# the second run: the group job with the failing subject failed once and was submitted again
run2 = [j for j in jobs.values() if int(j["id"]) > first]
assert [j["state"] for j in run2 if kind(j) == "snakejob_participant"].count("FAILED") == 1, run2
assert sorted(kind(j) for j in run2 if kind(j) != "snakejob_participant") == \
    ["snakejob_compare", "snakejob_evaluate", "snakejob_reference", "snakejob_reference_group"], run2
assert all(j["state"] == "COMPLETED" for j in run2 if j["state"] != "FAILED"), run2
# every job ran its rules as job steps (srun), but those cancelled before starting any
assert all(steps[j["id"]] >= 1 for j in jobs.values() if j["state"] in ("COMPLETED", "FAILED")), (jobs, steps)
print(f"slurm: {len(jobs)} Slurm jobs for the cohort, {len(groups)} of them participant group jobs")
PY
  { cat "$work/sacct.txt"; fail "the jobs Slurm saw"; }
echo "slurm workflow: ok ($((SECONDS - t0)) s)"
