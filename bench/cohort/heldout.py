#!/usr/bin/python3
"""Foci defaults chosen on one half of a set of generated cohorts and reported on the other
(issue 57; docs/cohort.md "Choosing detection defaults"). The cohorts are listed in a JSON spec
(bench/cohort/heldout.json: name, role development or report, and synth_cohort.py's settings).

  heldout.py run   --spec S --out DIR [--vpm PATH] [--cores 2] [--only NAMES]
      synthesises every cohort not yet there (DIR/NAME/bids) and runs the workflow at its defaults
      on it up to the foci's evaluation (DIR/NAME/results; not the cohort page), in the spec's
      order, recording each cohort's wall time in DIR/NAME/times.json.
  heldout.py score --spec S --out DIR --variants V [--vpm PATH] [--jobs 2] [--only NAMES]
      re-draws every cohort's foci with each `vpm compare` variant of V (a JSON list of
      {name, options}: compare flags over the workflow's own, as bench/cohort/compare_variants.py
      takes them; with "calibrate": FLAGS the variant is calibrated on the cohort's normals first,
      `vpm calibrate` with its comparison options and FLAGS, e.g. "--peak auto --rate 1" or
      "--tfce --rate 0.5", and compared with --min-cluster-from), chooses the variant with the
      best median Dice over the development cohorts among those with at most 1 false cluster per
      10 patients there (none when no variant is: the defaults stay), and writes DIR/heldout.json and
      DIR/heldout.md: every variant on every cohort, the median and worst over each role, and
      beside them the voxel-wise peer where `peer` has run. False clusters are evaluate.py's
      (native voxel pieces touching no planted focus), false foci the method's own foci touching
      none (a scoring kept from before false foci existed is counted again from its images).
  heldout.py peer  --spec S --out DIR [--jobs 2] [--only NAMES]
      runs the voxel-wise analysis after elastix (bench/cohort/voxelwise_elastix.py, its default
      setting: FWHM 8 mm, z <= -3, 340 mm^3) on every cohort with a finished workflow run, into
      DIR/NAME/results/peer_elastix/ (about 2.5 CPU-minutes a subject; a rerun reuses the
      registrations); `score` reports it scored the same way.

Exit 2 (one line on stderr) on a missing input or a failed step.
"""
import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import compare_variants  # noqa: E402
import evaluate  # noqa: E402
import lono  # noqa: E402


def fail(where, why):
    print(f"heldout.py: {where}: {why}", file=sys.stderr)
    sys.exit(2)


def load_spec(path):
    try:
        with open(path) as f:
            spec = json.load(f)
        cohorts = spec["cohorts"]
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(path, f"not a cohort spec ({e})")
    for c in cohorts:
        if c.get("role") not in ("development", "report") or not str(c.get("name", "")).isidentifier():
            fail(path, f"cohort {c.get('name')!r}: needs an identifier name and role development or report")
    return cohorts


def synth_argv(c, out):
    argv = ["/usr/bin/python3", os.path.join(ROOT, "scripts", "synth_cohort.py"), "--out", out,
            "--normals", str(int(c["normals"])), "--patients", str(int(c["patients"])),
            "--seed", str(int(c["seed"])), "--foci-free", str(int(c.get("foci_free", 0))),
            "--foci-per-patient", str(int(c.get("foci_per_patient", 2))),
            "--reduction", str(c.get("reduction", "0.15,0.30")), "--fwhm", str(float(c.get("fwhm", 8))),
            "--noise", str(float(c.get("noise", 0.05))), "--noise-fwhm", str(float(c.get("noise_fwhm", 4)))]
    return argv + (["--cortical"] if c.get("cortical") else [])


def step(argv, log):
    with open(log, "a") as f:
        r = subprocess.run(argv, stdout=f, stderr=subprocess.STDOUT)
    if r.returncode != 0:
        fail(log, f"{os.path.basename(argv[1] if argv[0].endswith('python3') else argv[0])} exit {r.returncode}")


def run(a):
    cohorts = load_spec(a.spec)
    only = set(a.only.split(",")) if a.only else None
    for c in cohorts:
        if only and c["name"] not in only:
            continue
        d = os.path.join(a.out, c["name"])
        os.makedirs(d, exist_ok=True)
        log = os.path.join(d, "run.log")
        times = {}
        t0 = time.time()
        if not os.path.exists(os.path.join(d, "bids", "participants.tsv")):
            step(synth_argv(c, os.path.join(d, "bids")) + ["--jobs", str(a.cores)], log)
        times["synth_s"] = round(time.time() - t0, 1)
        t1 = time.time()
        step(["snakemake", "-s", os.path.join(ROOT, "workflow", "Snakefile"), "--cores", str(a.cores),
              "--directory", d, "--config", f"bids={d}/bids", f"out={d}/results",
              "more_features={t1w: anat/T1w}", f"vpm={a.vpm}", "--", f"{d}/results/evaluation.json"], log)
        times["workflow_s"] = round(time.time() - t1, 1)
        with open(os.path.join(d, "times.json"), "w") as f:
            json.dump(times, f)
        print(f"{c['name']}: workflow {times['workflow_s']} s", flush=True)
    return 0


def score(a):
    cohorts = load_spec(a.spec)
    try:
        with open(a.variants) as f:
            variants = json.load(f)
        names = [v["name"] for v in variants]
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(a.variants, f"not a variant list ({e})")
    table = {}  # cohort -> variant -> summary
    only = set(a.only.split(",")) if a.only else None
    for c in cohorts:
        if only and c["name"] not in only:
            continue
        d = os.path.join(a.out, c["name"])
        if not os.path.exists(os.path.join(d, "results", "evaluation.json")):
            fail(d, "no finished workflow run (results/evaluation.json): run `heldout.py run` first")
        vout = os.path.join(d, "variants")
        os.makedirs(vout, exist_ok=True)
        done = os.path.join(vout, "variants.json")
        if os.path.exists(done):  # scored before with the same variants: kept
            with open(done) as f:
                got = json.load(f)["variants"]
            if [v["name"] for v in got] == names:
                table[c["name"]] = {v["name"]: with_false_foci(d, dict(v["summary"], patients=len(v["patients"])),
                                                               os.path.join(vout, v["name"], "compare"), "_pet")
                                    for v in got}
                continue
        argv = ["/usr/bin/python3", os.path.join(HERE, "compare_variants.py"), "--bids", os.path.join(d, "bids"),
                "--results", os.path.join(d, "results"), "--out", vout, "--vpm", a.vpm, "--jobs", str(a.jobs)]
        for v in variants:
            options = v.get("options", "")
            if "calibrate" in v:
                options += " " + calibrated(a, d, v, vout)
            argv += ["--variant", v["name"], options]
        step(argv, os.path.join(d, "score.log"))
        with open(done) as f:
            table[c["name"]] = {v["name"]: dict(v["summary"], patients=len(v["patients"]))
                               for v in json.load(f)["variants"]}
        print(f"{c['name']}: scored", flush=True)
    for c in cohorts:
        if c["name"] in table:
            p = peer_summary(os.path.join(a.out, c["name"]))
            if p:
                table[c["name"]][PEER] = with_false_foci(os.path.join(a.out, c["name"]), p,
                                                         os.path.join(a.out, c["name"], "results", "peer_elastix"), "")
    return 0 if only else report(a, cohorts, variants, table)


PEER = "voxel-wise after elastix"


def peer_summary(d):
    """The voxel-wise peer's default-setting summary on cohort folder d (with "patients"), or None."""
    path = os.path.join(d, "results", "peer_elastix", "evaluation.json")
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            e = json.load(f)
        s = next(x for x in e["settings"] if x["setting"] == e["default_setting"])
        return dict(s["summary"], patients=len(s["patients"]))
    except (OSError, ValueError, KeyError, StopIteration) as e:
        fail(path, f"not the peer's evaluation ({e})")


def with_false_foci(d, summary, folder, infix):
    """`summary` with false_foci (evaluate.score's) when a scoring written before it lacks them:
    counted again from the patients' detection images folder/sub-X{infix}_foci.nii.gz against
    cohort d's truth; left out when an image is gone."""
    if "false_foci" in summary:
        return summary
    _, patients = evaluate.read_participants(os.path.join(d, "bids"))
    total = 0
    for sid in patients:
        path = os.path.join(folder, f"{sid}{infix}_foci.nii.gz")
        if not os.path.exists(path):
            return summary
        det, _ = evaluate.load(path)
        truth, _ = evaluate.load(os.path.join(d, "bids", "derivatives", "truth", f"{sid}_foci.nii.gz"))
        total += evaluate.score(det, truth)["false_foci"]
    return dict(summary, false_foci=total)


def peer(a):
    only = set(a.only.split(",")) if a.only else None
    for c in load_spec(a.spec):
        if only and c["name"] not in only:
            continue
        d = os.path.join(a.out, c["name"])
        if not os.path.exists(os.path.join(d, "results", "evaluation.json")):
            fail(d, "no finished workflow run (results/evaluation.json): run `heldout.py run` first")
        t0 = time.time()
        step(["/usr/bin/python3", os.path.join(HERE, "voxelwise_elastix.py"), "--bids", os.path.join(d, "bids"),
              "--results", os.path.join(d, "results"), "--jobs", str(a.jobs)], os.path.join(d, "peer.log"))
        print(f"{c['name']}: peer done in {time.time() - t0:.0f} s", flush=True)
    return 0


def calibrated(a, d, v, vout):
    """`vpm calibrate` of variant v on cohort d's normals (its comparison options, v's calibrate
    flags); returns the compare flags that apply it."""
    base, _ = lono.workflow_options(os.path.join(d, "results"), "pet")
    options = compare_variants.merged(base, shlex.split(v.get("options", "")) + ["--min-cluster", "-", "--peak", "-"])
    bids = os.path.join(d, "bids")
    normals, _ = evaluate.read_participants(bids)
    tables = os.path.join(d, "results", "tables")
    out = os.path.join(vout, f"calibration_{v['name']}.json")
    if not os.path.exists(out):
        argv = [a.vpm, "calibrate", "--normals", ",".join(os.path.join(tables, f"{n}_pet.h5") for n in normals),
                "--feature", "pet", *options, *shlex.split(v["calibrate"]), "-o", out, "--quiet"]
        r = subprocess.run(argv, capture_output=True, text=True)
        if r.returncode != 0:
            fail(out, f"vpm calibrate exit {r.returncode}: {r.stderr.strip()[-300:]}")
    return f"--min-cluster - --peak - --min-cluster-from {shlex.quote(out)}"


def row(summaries):
    """Median and worst over cohorts of Dice, overlap, precision; foci found and false clusters summed."""
    dice = [s["pooled"]["dice"] or 0.0 for s in summaries]
    ov = [s["pooled"]["sensitivity"] or 0.0 for s in summaries]
    pr = [s["pooled"]["precision"] or 0.0 for s in summaries]
    patients = sum(s.get("patients", 0) for s in summaries)
    false = sum(s["false_positive_clusters"] for s in summaries)
    foci = sum(s["false_foci"] for s in summaries) if all("false_foci" in s for s in summaries) else None
    return {"dice_median": statistics.median(dice), "dice_worst": min(dice),
            "overlap_median": statistics.median(ov), "overlap_worst": min(ov),
            "precision_median": statistics.median(pr), "precision_worst": min(pr),
            "found": sum(s["foci_found"] for s in summaries), "planted": sum(s["foci_planted"] for s in summaries),
            "false_clusters": false, "patients": patients,
            "false_per_10_patients": 10.0 * false / patients if patients else None,
            "false_foci": foci, "false_foci_per_10_patients": 10.0 * foci / patients if patients and foci is not None else None}


def foci_cell(s):
    return "n/a" if s["false_foci"] is None else f"{s['false_foci']} ({s['false_foci_per_10_patients']:.1f})"


def report(a, cohorts, variants, table):
    roles = {r: [c["name"] for c in cohorts if c["role"] == r] for r in ("development", "report")}
    res = {"spec": a.spec, "variants": variants, "cohorts": cohorts, "per_cohort": table, "by_role": {}}
    for r, names in roles.items():
        res["by_role"][r] = {v["name"]: row([table[n][v["name"]] for n in names]) for v in variants}
    for r, names in roles.items():  # the peer over the cohorts it ran on
        have = [n for n in names if PEER in table[n]]
        if have:
            res["by_role"][r][PEER] = dict(row([table[n][PEER] for n in have]), cohorts=have)
    dev = res["by_role"]["development"]
    ok = [v["name"] for v in variants if (dev[v["name"]]["false_per_10_patients"] or 0) <= 1.0]
    chosen = max(ok, key=lambda n: (dev[n]["dice_median"], dev[n]["dice_worst"])) if ok else None
    res["chosen"] = chosen
    res["chosen_within_false_rate"] = bool(ok)
    pct = lambda x: f"{100 * x:.1f}"
    if ok:
        lines = [f"Chosen on the development cohorts ({', '.join(roles['development'])}): **{chosen}** (best median "
                 "Dice among the variants with at most 1 false cluster per 10 patients there).", ""]
    else:
        lines = [f"None chosen on the development cohorts ({', '.join(roles['development'])}): no variant kept to 1 "
                 "false cluster per 10 patients there, so the workflow's defaults stay.", ""]
    for r in ("development", "report"):
        lines += [f"### {r} cohorts ({', '.join(roles[r])})", "",
                  "| variant | options | Dice median / worst | overlap median / worst | precision median / worst | found | "
                  "false clusters (per 10 patients) | false foci (per 10 patients) |",
                  "|---|---|---|---|---|---|---|---|"]
        for v in variants:
            s = res["by_role"][r][v["name"]]
            mark = "**" if v["name"] == chosen else ""
            opts = " ".join(x for x in (v.get("options", ""), "calibrate " + v["calibrate"] if "calibrate" in v else "") if x)
            lines.append(f"| {mark}{v['name']}{mark} | {opts or '(workflow defaults)'} | "
                         f"{pct(s['dice_median'])} / {pct(s['dice_worst'])} | {pct(s['overlap_median'])} / "
                         f"{pct(s['overlap_worst'])} | {pct(s['precision_median'])} / {pct(s['precision_worst'])} | "
                         f"{s['found']}/{s['planted']} | {s['false_clusters']} ({s['false_per_10_patients']:.1f}) | "
                         f"{foci_cell(s)} |")
        if PEER in res["by_role"][r]:
            s = res["by_role"][r][PEER]
            lines.append(f"| {PEER} | FWHM 8 mm, z <= -3, 340 mm^3 (on {', '.join(s['cohorts'])}) | "
                         f"{pct(s['dice_median'])} / {pct(s['dice_worst'])} | {pct(s['overlap_median'])} / "
                         f"{pct(s['overlap_worst'])} | {pct(s['precision_median'])} / {pct(s['precision_worst'])} | "
                         f"{s['found']}/{s['planted']} | {s['false_clusters']} ({s['false_per_10_patients']:.1f}) | "
                         f"{foci_cell(s)} |")
        lines.append("")
    lines += ["### every cohort (Dice / found / false clusters / false foci)", "",
              "| variant | " + " | ".join(f"{c['name']} ({c['role'][0]})" for c in cohorts) + " |",
              "|---|" + "---|" * len(cohorts)]
    for name in [v["name"] for v in variants] + [PEER]:
        cells = []
        for c in cohorts:
            s = table[c["name"]].get(name)
            cells.append(f"{pct(s['pooled']['dice'] or 0.0)} / {s['foci_found']}/{s['foci_planted']} / "
                         f"{s['false_positive_clusters']} / {s.get('false_foci', 'n/a')}" if s else "not run")
        if name != PEER or any(PEER in table[c["name"]] for c in cohorts):
            lines.append(f"| {name} | " + " | ".join(cells) + " |")
    with open(os.path.join(a.out, "heldout.json"), "w") as f:
        json.dump(res, f, indent=1)
    with open(os.path.join(a.out, "heldout.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    for name in ("run", "score", "peer"):
        p = sub.add_parser(name)
        p.add_argument("--spec", default=os.path.join(HERE, "heldout.json"))
        p.add_argument("--out", required=True)
        p.add_argument("--vpm", default=os.path.join(ROOT, "build", "vpm"))
        if name == "run":
            p.add_argument("--cores", type=int, default=2)
            p.add_argument("--only", default="")
        elif name == "peer":
            p.add_argument("--jobs", type=int, default=2)
            p.add_argument("--only", default="")
        else:
            p.add_argument("--variants", required=True)
            p.add_argument("--jobs", type=int, default=2)
            p.add_argument("--only", default="", help="score these cohorts only (no report); a later run reuses them")
    a = ap.parse_args()
    a.out = os.path.abspath(a.out)
    return {"run": run, "score": score, "peer": peer}[a.cmd](a)


if __name__ == "__main__":
    sys.exit(main())
