#!/usr/bin/env python3
"""Two builds of vpm side by side on the same benchmarks, interleaved, for "is B slower than A".

    python3 bench/ab/compare_builds.py --a OLD_BUILD --b NEW_BUILD --out DIR [--rounds 5]
        [--warmup 1] [--cases volume_map,register,...] [--mesh MESH.vtu] [--threshold 0.03]
        [--instructions | --profile]

Each round runs every case once with each build, the order alternating (A B, then B A), so a
machine that drifts slower affects both alike. The first --warmup rounds (PoCL's kernel builds,
cold caches) are run and dropped. A case's timings are the benchmark's own JSON timing fields
(keys ending in _s, _s_median or seconds, and the fields of timings_s_median / median_s) plus the
whole command's wall and CPU seconds. Per timing: the median over rounds of each build, the ratio
B / A of the medians and of the minima, and A's own spread (max - min) / median over its rounds,
the noise a ratio has to be read against. A timing counts as slower only when both ratios exceed
1 + threshold; `noisy` when A's spread exceeds the threshold (then only a larger difference means
anything). Writes DIR/compare.json and prints the table; the builds' outputs are kept in
DIR/<case>/<a|b>/<round>/.

With --instructions each case runs once per build under valgrind's cachegrind instead, which
counts the instructions executed (I refs, the PoCL kernels' included): a count does not move
with the machine's load, where wall times on a shared 2-core VM spread by 10-80 % between runs
of the same build. The two builds run side by side (valgrind runs a program's threads one at a
time, so each takes one core), twice, and the second run is counted: the first fills the PoCL
kernel cache for the CPU valgrind presents, so kernel compilation stays out of the count. The cases are lighter (INSTR_CASES). A count is a
proxy for time, not a time: memory traffic and parallel efficiency are not in it.

With --profile each run is sampled by `perf record -e cpu-clock` (a software clock: the VM
exposes no hardware counters) and the samples are summed per shared object (the library, libm,
each PoCL kernel's .so) over the rounds: a machine that runs slower scales every row alike,
where a code change moves its own row. Printed: samples per row for A and B, B / A, and B / A
of the row's share of all samples (1 = the same fraction of the run). Writes DIR/profile.json.

A build folder is what scripts/build.sh makes (vpm, bench/vpm_bench_*); the command runs with
POCL_CACHE_DIR=DIR/pocl-cache-<a|b>. Exit 1 when a timing is slower, else 0.
"""
import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import time

CASES = {
    # name: (command template, JSON file written under {O} or None, extra environment)
    "volume_map": ("{B}/bench/vpm_bench_volume_map --runs 1 --out {O}", "volume_map.json", {}),
    "register": ("{B}/bench/vpm_bench_register --quick --runs 5 --out {O}/register.json", "register.json", {}),
    "solver": ("{B}/bench/vpm_bench_solver --sizes 25000,100000 --repeats 3 --no-viennacl --no-eigen "
               "--no-hypre --json {O}/solver.json", "solver.json", {}),
    "harmonic": ("{B}/bench/vpm_bench_harmonic --repeats 3 --json {O}/harmonic.json", "harmonic.json", {}),
    "sphere_map": ("{B}/bench/vpm_bench_sphere_map --sizes 100000 --repeats 3 --json {O}/sphere_map.json",
                   "sphere_map.json", {}),
    "initial_map": ("{B}/bench/vpm_bench_initial_map --runs 1 --out {O}/initial_map.json", "initial_map.json", {}),
    "demo_host": ("{B}/vpm demo --out {O}/demo", "demo/demo.json", {"VPM_DEVICE": "host"}),
    "demo_pocl": ("{B}/vpm demo --out {O}/demo", "demo/demo.json", {"VPM_DEVICE": "cpu"}),
    "map_mesh": ("{B}/vpm map {MESH} -o {O}/map.vtu --report {O}/map.json", "map.json", {}),
    "mesh_image": ("{B}/bench/vpm_bench_mesh_image --runs 1 --out {O}/mesh_image.json", "mesh_image.json", {}),
    "io": ("{B}/bench/vpm_bench_io 40 {O}", "bench_io.json", {}),
}
# lighter settings for --instructions (valgrind runs 50-300x slower than the program)
INSTR_CASES = {
    "register": ("{B}/bench/vpm_bench_register --quick --runs 1 --out {O}/register.json", "register.json", {}),
    "solver": ("{B}/bench/vpm_bench_solver --sizes 25000,100000 --repeats 1 --no-viennacl --no-eigen --no-hypre "
               "--json {O}/solver.json", "solver.json", {}),
    "harmonic": ("{B}/bench/vpm_bench_harmonic --sizes 100000 --repeats 1 --json {O}/harmonic.json", "harmonic.json", {}),
    "sphere_map": ("{B}/bench/vpm_bench_sphere_map --sizes 100000 --repeats 1 --json {O}/sphere_map.json",
                   "sphere_map.json", {}),
    "initial_map": CASES["initial_map"],
    "map_host": ("{B}/vpm map {MESH} -o {O}/map.vtu", None, {"VPM_DEVICE": "host"}),
    "map_pocl": ("{B}/vpm map {MESH} -o {O}/map.vtu", None, {"VPM_DEVICE": "cpu"}),
}
INSTR_DEFAULT = ["register", "solver", "harmonic", "sphere_map", "initial_map", "map_host", "map_pocl"]
DEFAULT = ["volume_map", "register", "solver", "harmonic", "sphere_map", "initial_map", "demo_host", "demo_pocl"]
IDENTITY = ("name", "mesh", "case", "solver", "method", "shape")
TIMING_PARENTS = ("timings_s_median", "median_s")


def is_timing(key, parent):
    if "per_s" in key:
        return False  # a rate, not a duration
    return parent in TIMING_PARENTS or re.search(r"(_s|_s_median|seconds)$", key) is not None


def timings(obj, path="", parent="", out=None):
    """The timing leaves of a benchmark's JSON, lists labelled by their elements' identity keys."""
    out = {} if out is None else out
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k in ("report", "reports", "times_s", "time_s_all", "setup_update_times_s"):
                continue  # per-round detail and the raw samples behind a median
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                if is_timing(k, parent):
                    out[f"{path}.{k}".lstrip(".")] = float(v)
            else:
                timings(v, f"{path}.{k}", k, out)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            label = str(i)
            if isinstance(v, dict):
                ids = [str(v[k]) for k in IDENTITY if k in v and not isinstance(v[k], (dict, list))]
                label = "/".join(ids) or label
            timings(v, f"{path}[{label}]", parent, out)
    return out


def run_case(case, build, outdir, env_extra, mesh, pocl_cache):
    cmd_t, json_name, env_case = CASES[case]
    os.makedirs(outdir, exist_ok=True)
    cmd = cmd_t.format(B=build, O=outdir, MESH=mesh or "")
    env = dict(os.environ, POCL_CACHE_DIR=pocl_cache, **env_case, **env_extra)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with open(os.path.join(outdir, "log.txt"), "w") as log:
        rc = subprocess.run(cmd.split(), env=env, stdout=log, stderr=subprocess.STDOUT).returncode
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if rc != 0:
        sys.exit(f"compare_builds: {case} failed with {build} (exit {rc}); see {outdir}/log.txt")
    res = {"wall_s": wall, "cpu_s": (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)}
    path = os.path.join(outdir, json_name)
    if json_name and os.path.exists(path):
        with open(path) as f:
            res.update(timings(json.load(f)))
    return res


VALGRIND = ["valgrind", "--tool=cachegrind", "--cache-sim=no", "--branch-sim=no", "--cachegrind-out-file=/dev/null"]


def instructions(case, builds, out, mesh):
    """I refs of one case per build: two valgrind runs of each, the builds side by side, the
    second run counted (the first fills PoCL's kernel cache for the CPU valgrind presents, which
    lacks the host's AVX-512: native runs would not)."""
    cmd_t, _, env_case = INSTR_CASES[case]
    counts = {}
    for attempt in ("warm", "count"):
        procs = {}
        for k, build in builds.items():
            outdir = os.path.join(out, "instructions", case, k)
            os.makedirs(outdir, exist_ok=True)
            cmd = cmd_t.format(B=build, O=outdir, MESH=mesh or "").split()
            env = dict(os.environ, POCL_CACHE_DIR=os.path.join(os.path.abspath(out), f"pocl-cache-{k}"), **env_case)
            log = open(os.path.join(outdir, f"{attempt}.txt"), "w")
            procs[k] = (subprocess.Popen(VALGRIND + cmd, env=env, stdout=log, stderr=subprocess.STDOUT), log, outdir)
        for k, (proc, log, outdir) in procs.items():
            rc = proc.wait()
            log.close()
            text = open(os.path.join(outdir, f"{attempt}.txt")).read()
            m = re.search(r"I\s+refs:\s+([\d,]+)", text)
            if rc != 0 or not m:
                sys.exit(f"compare_builds: {case} under valgrind failed with {builds[k]}; see {outdir}/{attempt}.txt")
            counts[k] = int(m.group(1).replace(",", ""))
    return counts


def main_instructions(args, builds):
    cases = [c for c in (args.cases or ",".join(INSTR_DEFAULT)).split(",") if c]
    for c in cases:
        if c not in INSTR_CASES:
            sys.exit(f"compare_builds: unknown case {c!r} for --instructions (known: {', '.join(INSTR_CASES)})")
        if c.startswith("map_") and not args.mesh:
            sys.exit(f"compare_builds: the case {c} needs --mesh")
    rows, slower = [], []
    print(f"{'case':12} {'A instructions':>16} {'B instructions':>16} {'B/A':>7}")
    for c in cases:
        n = instructions(c, builds, args.out, args.mesh)
        ratio = n["b"] / n["a"]
        rows.append({"case": c, "a": n["a"], "b": n["b"], "ratio": ratio})
        if ratio > 1 + args.threshold:
            slower.append(c)
        print(f"{c:12} {n['a']:16,d} {n['b']:16,d} {ratio:7.4f}", flush=True)
    with open(os.path.join(args.out, "instructions.json"), "w") as f:
        json.dump({"a": builds["a"], "b": builds["b"], "threshold": args.threshold, "cases": rows,
                   "slower": slower}, f, indent=1)
    print(f"\nmore instructions than A by more than {args.threshold:.0%}: {', '.join(slower) if slower else 'none'}")
    return 1 if slower else 0


def perf_rows(data):
    """Samples per shared object of one perf.data."""
    text = subprocess.run(["perf", "report", "-i", data, "--stdio", "--sort", "dso", "-F", "sample,dso"],
                          capture_output=True, text=True).stdout
    rows = {}
    for line in text.splitlines():
        parts = line.split()
        if len(parts) >= 2 and not line.startswith("#") and parts[0].isdigit():
            rows[parts[1]] = rows.get(parts[1], 0) + int(parts[0])
    return rows


def main_profile(args, builds):
    cases = [c for c in (args.cases or ",".join(DEFAULT)).split(",") if c]
    totals = {c: {"a": {}, "b": {}} for c in cases}
    for r in range(args.warmup + args.rounds):
        for c in cases:
            for k in (["a", "b"] if r % 2 == 0 else ["b", "a"]):
                outdir = os.path.join(args.out, "profile", c, k, str(r))
                os.makedirs(outdir, exist_ok=True)
                cmd_t, _, env_case = CASES[c]
                cmd = cmd_t.format(B=builds[k], O=outdir, MESH=args.mesh or "").split()
                env = dict(os.environ, POCL_CACHE_DIR=os.path.join(os.path.abspath(args.out), f"pocl-cache-{k}"),
                           **env_case)
                data = os.path.join(outdir, "perf.data")
                with open(os.path.join(outdir, "log.txt"), "w") as log:
                    rc = subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", "999", "-o", data, "--"] + cmd,
                                        env=env, stdout=log, stderr=subprocess.STDOUT).returncode
                if rc != 0:
                    sys.exit(f"compare_builds: {c} failed under perf with {builds[k]}; see {outdir}/log.txt")
                if r >= args.warmup:
                    for dso, n in perf_rows(data).items():
                        totals[c][k][dso] = totals[c][k].get(dso, 0) + n
                os.remove(data)
            print(f"round {r + 1}/{args.warmup + args.rounds} {c} done", flush=True)
    report = {"a": builds["a"], "b": builds["b"], "rounds": args.rounds, "cases": {}}
    print(f"\n{'case':12} {'shared object':28} {'A samples':>10} {'B samples':>10} {'B/A':>7} {'share B/A':>9}")
    for c in cases:
        a, b = totals[c]["a"], totals[c]["b"]
        ta, tb = max(1, sum(a.values())), max(1, sum(b.values()))
        rows = []
        for dso in sorted(set(a) | set(b), key=lambda d: -(a.get(d, 0) + b.get(d, 0))):
            na, nb = a.get(dso, 0), b.get(dso, 0)
            if max(na / ta, nb / tb) < 0.01:
                continue  # under 1 % of the run on both sides
            ratio = nb / na if na else float("inf")
            share = (nb / tb) / (na / ta) if na else float("inf")
            rows.append({"object": dso, "a": na, "b": nb, "ratio": ratio, "share_ratio": share})
            print(f"{c:12} {dso[:28]:28} {na:10d} {nb:10d} {ratio:7.3f} {share:9.3f}")
        print(f"{c:12} {'(all)':28} {ta:10d} {tb:10d} {tb / ta:7.3f}")
        report["cases"][c] = {"a_total": ta, "b_total": tb, "rows": rows}
    with open(os.path.join(args.out, "profile.json"), "w") as f:
        json.dump(report, f, indent=1)
    return 0


def summarise(samples_a, samples_b, threshold):
    rows = []
    for key in sorted(set(samples_a) & set(samples_b)):
        a, b = samples_a[key], samples_b[key]
        if len(a) != len(b) or not a or min(a) <= 0 or min(b) <= 0:
            continue
        ma, mb = statistics.median(a), statistics.median(b)
        r_med, r_min = mb / ma, min(b) / min(a)
        spread = (max(a) - min(a)) / ma
        verdict = "slower" if r_med > 1 + threshold and r_min > 1 + threshold else (
            "faster" if r_med < 1 - threshold and r_min < 1 - threshold else "same")
        rows.append({"timing": key, "a_median": ma, "b_median": mb, "ratio_median": r_med, "ratio_min": r_min,
                     "a_spread": spread, "noisy": spread > threshold, "verdict": verdict, "a": a, "b": b})
    return rows


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--a", required=True, help="the reference build folder")
    p.add_argument("--b", required=True, help="the build compared with it")
    p.add_argument("--out", required=True)
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--warmup", type=int, default=1)
    p.add_argument("--cases", help="comma-separated (default: every case of the mode)")
    p.add_argument("--instructions", action="store_true", help="count instructions under valgrind instead")
    p.add_argument("--profile", action="store_true", help="sample where the time goes with perf instead")
    p.add_argument("--mesh", help="a mesh for the case map_mesh (vpm map)")
    p.add_argument("--threshold", type=float, default=0.03)
    p.add_argument("--min-seconds", type=float, default=0.05,
                   help="timings whose A median is below this are listed but not judged")
    args = p.parse_args()
    builds = {"a": os.path.abspath(args.a), "b": os.path.abspath(args.b)}
    for k, b in builds.items():
        if not os.path.exists(os.path.join(b, "vpm")):
            sys.exit(f"compare_builds: --{k} {b} holds no vpm")
    os.makedirs(args.out, exist_ok=True)
    if args.instructions:
        return main_instructions(args, builds)
    if args.profile:
        return main_profile(args, builds)
    cases = [c for c in (args.cases or ",".join(DEFAULT)).split(",") if c]
    for c in cases:
        if c not in CASES:
            sys.exit(f"compare_builds: unknown case {c!r} (known: {', '.join(CASES)})")
        if c == "map_mesh" and not args.mesh:
            sys.exit("compare_builds: the case map_mesh needs --mesh")
    samples = {c: {"a": {}, "b": {}} for c in cases}
    total = args.warmup + args.rounds
    for r in range(total):
        order = ["a", "b"] if r % 2 == 0 else ["b", "a"]
        for c in cases:
            for k in order:
                outdir = os.path.join(args.out, c, k, str(r))
                res = run_case(c, builds[k], outdir, {}, args.mesh,
                               os.path.join(os.path.abspath(args.out), f"pocl-cache-{k}"))
                if r >= args.warmup:
                    for key, v in res.items():
                        samples[c][k].setdefault(key, []).append(v)
            print(f"round {r + 1}/{total} {c} done", flush=True)
    report = {"a": builds["a"], "b": builds["b"], "rounds": args.rounds, "warmup": args.warmup,
              "threshold": args.threshold, "load_average_end": os.getloadavg(), "cases": {}}
    slower = []
    print(f"\n{'case':12} {'timing':58} {'A med':>9} {'B med':>9} {'B/A med':>8} {'B/A min':>8} {'A spread':>8}  verdict")
    for c in cases:
        rows = summarise(samples[c]["a"], samples[c]["b"], args.threshold)
        report["cases"][c] = rows
        for row in rows:
            judged = row["a_median"] >= args.min_seconds
            v = row["verdict"] if judged else "too short"
            if judged and row["verdict"] == "slower":
                slower.append(f"{c}:{row['timing']}")
            print(f"{c:12} {row['timing'][:58]:58} {row['a_median']:9.4f} {row['b_median']:9.4f} "
                  f"{row['ratio_median']:8.3f} {row['ratio_min']:8.3f} {row['a_spread']:8.3f}  {v}"
                  f"{' (noisy)' if row['noisy'] and judged else ''}")
    report["slower"] = slower
    with open(os.path.join(args.out, "compare.json"), "w") as f:
        json.dump(report, f, indent=1)
    print(f"\nslower than A by more than {args.threshold:.0%} on both the median and the minimum: "
          f"{', '.join(slower) if slower else 'none'}")
    return 1 if slower else 0


if __name__ == "__main__":
    sys.exit(main())
