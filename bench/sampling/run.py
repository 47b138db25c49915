#!/usr/bin/env python3
"""Times `vpm sample` and the sampling paths on one registered mesh, interleaved, and writes the
medians (bench/results/issue54_sampling_*).

    bench/sampling/run.py --build BUILD --out DIR [--old-vpm OLD/vpm] [--repeats 3]
                          [--level 6] [--layout graded] [--samples 8]

The mesh: BUILD/vpm mesh-image ch2bet (45,000 target vertices) mapped to the ball by BUILD/vpm
map (made once in DIR/work; a ball map is a valid registered mesh for timing). Images: ch2bet as
`pet`, ch2 as `t1w` (/usr/share/mricron/templates). Each round runs every case once, in turn:

  old_vpm      --old-vpm's `vpm sample` (a build from before the element sampler), VPM_DEVICE=host
  vpm_host     BUILD's `vpm sample`, VPM_DEVICE=host
  vpm_cpu      BUILD's `vpm sample`, VPM_DEVICE=cpu (PoCL selected; sampling placed as it decides)
  path_old     vpm_bench_sampling --path old (every sample held, pulled back at once)
  path_host    vpm_bench_sampling --path host (ElementSampler, host threads)
  path_pocl    vpm_bench_sampling --path device, VPM_DEVICE=cpu (ElementSampler's kernels on PoCL)

Wall time and peak resident memory come from /usr/bin/time; the vpm_bench_sampling cases add
their steps (sampling apart from writing the TSV). Nothing is asserted.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys

TEMPLATES = pathlib.Path("/usr/share/mricron/templates")


def timed(cmd, env):
    """(wall s, peak RSS MB, stdout) of cmd under /usr/bin/time."""
    r = subprocess.run(["/usr/bin/time", "-f", "TIME %e %M"] + cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stderr[-2000:]}")
    line = [l for l in r.stderr.splitlines() if l.startswith("TIME ")][-1].split()
    return float(line[1]), float(line[2]) / 1024.0, r.stdout


def make_mesh(vpm, work, env):
    ball = work / "ball.vtu"
    if not ball.exists():
        work.mkdir(parents=True, exist_ok=True)
        subprocess.run([vpm, "mesh-image", str(TEMPLATES / "ch2bet.nii.gz"), "-o", str(work / "m.vtu"),
                        "--target-vertices", "45000", "--quiet"], env=env, check=True)
        subprocess.run([vpm, "map", str(work / "m.vtu"), "-o", str(ball), "--quiet"], env=env, check=True)
    return ball


def cases(args, ball, work):
    images = f"pet={TEMPLATES / 'ch2bet.nii.gz'},t1w={TEMPLATES / 'ch2.nii.gz'}"
    definition = ["--layout", args.layout, "--level", str(args.level), "--samples", str(args.samples)]
    vpm = str(pathlib.Path(args.build) / "vpm")
    bench = str(pathlib.Path(args.build) / "bench" / "vpm_bench_sampling")
    sample = lambda exe, tag: [exe, "sample", str(ball), "-o", str(work / f"{tag}.tsv"), "--images", images] + definition
    path = lambda p, tag: [bench, str(ball), "--images", images, "--path", p, "--out", str(work / f"{tag}.tsv")] + definition
    out = []
    if args.old_vpm:
        out.append(("old_vpm", sample(args.old_vpm, "old_vpm"), "host"))
    out += [("vpm_host", sample(vpm, "vpm_host"), "host"), ("vpm_cpu", sample(vpm, "vpm_cpu"), "cpu"),
            ("path_old", path("old", "path_old"), "host"), ("path_host", path("host", "path_host"), "host"),
            ("path_pocl", path("device", "path_pocl"), "cpu")]
    return out


def compare(a, b):
    """Rows of TSV a and b that differ, and the largest absolute difference of a value."""
    rows = worst = 0
    with open(a) as fa, open(b) as fb:
        if fa.readline() != fb.readline():
            return {"header": "differs"}
        for la, lb in zip(fa, fb):
            if la == lb:
                continue
            rows += 1
            worst = max([worst] + [abs(float(x) - float(y)) for x, y in zip(la.split("\t"), lb.split("\t"))])
    return {"rows_differing": rows, "max_abs_difference": worst}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--old-vpm")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--level", type=int, default=6)
    ap.add_argument("--layout", default="graded")
    ap.add_argument("--samples", type=int, default=8)
    args = ap.parse_args()
    out = pathlib.Path(args.out)
    work = out / "work"
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", str(pathlib.Path(args.build).resolve() / "pocl-cache"))
    ball = make_mesh(str(pathlib.Path(args.build) / "vpm"), work, dict(env, VPM_DEVICE="host"))
    runs = {}
    todo = cases(args, ball, work)
    for tag, cmd, device in todo:  # a warm-up round: PoCL's kernel cache, the page cache
        timed(cmd, dict(env, VPM_DEVICE=device))
    for r in range(args.repeats):
        for tag, cmd, device in todo:
            wall, rss, stdout = timed(cmd, dict(env, VPM_DEVICE=device))
            run = {"wall_s": wall, "peak_rss_mb": rss}
            if tag.startswith("path_"):
                run["report"] = json.loads(stdout)
            runs.setdefault(tag, []).append(run)
            print(f"round {r + 1} {tag}: {wall:.2f} s, {rss:.0f} MB", flush=True)
    summary = {}
    for tag, rs in runs.items():
        s = {"runs": len(rs), "wall_s": statistics.median(x["wall_s"] for x in rs),
             "peak_rss_mb": statistics.median(x["peak_rss_mb"] for x in rs)}
        if "report" in rs[0]:
            for k in rs[0]["report"]["steps"]:
                if k.endswith("_s"):
                    s[k] = statistics.median(x["report"]["steps"][k] for x in rs)
        summary[tag] = s
    same = {tag: compare(work / "vpm_host.tsv", work / f"{tag}.tsv") for tag, _, _ in todo if tag != "vpm_host"}
    result = {"mesh": str(ball), "tables_against_vpm_host": same, "tets": runs["path_host"][0]["report"]["tets"],
              "definition": runs["path_host"][0]["report"]["definition"],
              "elements": runs["path_host"][0]["report"]["elements"], "nproc": os.cpu_count(),
              "loadavg_at_end": os.getloadavg(), "median": summary, "runs": runs}
    (out / "results.json").write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
