#!/usr/bin/env python3
"""Collects bench/paper's results (bench/paper/run.sh) into RESULTS/paper.json, RESULTS/paper.md
(the reproduced Tables 1 and 2 beside the paper's numbers) and RESULTS/fig3.png (Fig. 3: histograms
of log vertex volume ratio, harmonic map in red, volume-preserving map in blue, x from -0.6 to 0.6
with ticks every 0.1 (long at 0), y the fraction of vertices on a log scale from 1e-4 to 1; drawn
with numpy and zlib, no plotting library). Usage: tables.py RESULTS   (default bench/results/paper)"""
import glob
import json
import os
import statistics
import struct
import sys
import zlib

import numpy as np

PAPER_T1 = {"harmonic": (3.09, 32.3), "volume": (2.32, 12.9)}
PAPER_DICE = [0.637, 0.664, 0.768, 0.756]
NAMES = ["Caudate_L", "Caudate_R", "Thalamus_L", "Thalamus_R"]


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def table1(tables):
    rows = ["| flow | map | displacement (% of radius) | vertex mean abs(r-1) | tet mean abs(r-1) | paper: displacement / distortion |",
            "|---|---|---|---|---|---|"]
    for t1 in tables:
        m = t1["median"]
        for key, label in (("harmonic", "initial (harmonic) map"), ("volume", "volume-preserving map")):
            rows.append("| x%g | %s | %.2f %% | %.2f %% | %.2f %% | %.2f %% / %.1f %% |" % (
                t1.get("amplitude", 1), label, 100 * m[key + "_displacement"], 100 * m[key + "_vertex_mean_abs_dev"],
                100 * m[key + "_tet_mean_abs_dev"], *PAPER_T1[key]))
    return rows


def table2(runs, failed):
    out = {}
    rows = ["| registration | " + " | ".join(NAMES) + " | vertex / tet abs(r-1) | runs (failed) |", "|---" * 7 + "|"]
    for dense, label in ((0, "landmarks only"), (12, "dense (12 iterations)")):
        sel = [r for (s, d), r in sorted(runs.items()) if d == dense]
        if not sel:
            continue
        dice = [med([r["overlap"]["held_out"][i]["dice_image_after"] for r in sel]) for i in range(4)]
        vd = med([r["registration"]["vertex_volume_ratio"]["mean_abs_dev"] for r in sel])
        td = med([r["registration"]["tet_volume_ratio"]["mean_abs_dev"] for r in sel])
        out[label] = {"dice_median": dict(zip(NAMES, dice)), "vertex_mean_abs_dev": vd, "tet_mean_abs_dev": td,
                      "runs": len(sel), "per_seed": [{"seed": s, "rotation_deg": r["deformation"]["rotation_deg"],
                      "dice": [o["dice_image_after"] for o in r["overlap"]["held_out"]],
                      "dice_before": [o["dice_image_before"] for o in r["overlap"]["held_out"]],
                      "vertex_mean_abs_dev": r["registration"]["vertex_volume_ratio"]["mean_abs_dev"],
                      "seconds": r["timings_s"]["total"]} for (s, d), r in sorted(runs.items()) if d == dense]}
        nf = sum(1 for (s, d) in failed if d == dense)
        out[label]["failed_seeds"] = sorted(s for (s, d) in failed if d == dense)
        rows.append("| %s | %s | %.2f %% / %.2f %% | %d (%d) |" % (
            label, " | ".join("%.3f" % x for x in dice), 100 * vd, 100 * td, len(sel), nf))
    rows.append("| paper (Hu et al. 2014) | %s | 3.0 %% | |" % " | ".join("%.3f" % x for x in PAPER_DICE))
    return rows, out


def png(path, rgb):
    h, w, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].astype(np.uint8).tobytes() for y in range(h))
    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def fig3(hist, path, w=640, h=360, margin=40):
    img = np.full((h, w, 3), 255, np.uint8)
    hv, hh = np.array(hist["volume"]["counts"], float), np.array(hist["harmonic"]["counts"], float)
    n = len(hv)
    bw = (w - 2 * margin) / n
    for counts, colour, shrink in ((hh, (220, 60, 50), 0), (hv, (40, 90, 220), 0.25)):
        share = counts / counts.sum()  # log scale: 1e-4 at the axis, 1 at the top
        frac = np.where(share > 0, np.clip((np.log10(np.maximum(share, 1e-12)) + 4) / 4, 0, 1), 0)
        for i, f in enumerate(frac):
            x0, x1 = int(margin + (i + shrink) * bw), int(margin + (i + 1 - shrink) * bw) - 1
            y0 = int(h - margin - f * (h - 2 * margin))
            img[y0:h - margin, x0:max(x1, x0 + 1)] = colour
    img[h - margin:h - margin + 2, margin:w - margin] = 0          # x axis (log r from lo to hi)
    img[margin:h - margin + 2, margin:margin + 2] = 0              # y axis (fraction of vertices)
    lo, hi = hist["volume"]["lo"], hist["volume"]["hi"]
    for t in np.arange(lo, hi + 1e-9, 0.1):                        # ticks every 0.1 in log r
        x = int(margin + (t - lo) / (hi - lo) * (w - 2 * margin))
        img[h - margin:h - margin + (12 if abs(t) < 1e-9 else 6), x:x + 2] = 0
    for d in range(5):                                             # decades 1e-4 .. 1
        y = int(h - margin - d / 4 * (h - 2 * margin))
        img[y:y + 2, margin - 6:margin] = 0
    png(path, img)


def main():
    res = sys.argv[1] if len(sys.argv) > 1 else "bench/results/paper"
    t1 = json.load(open(os.path.join(res, "table1.json")))
    t1s = [t1] + [json.load(open(f)) for f in sorted(glob.glob(os.path.join(res, "table1_x*.json")))]
    runs = {}
    for f in glob.glob(os.path.join(res, "table2", "seed*_dense*.json")):
        s, d = os.path.basename(f)[4:-5].split("_dense")
        runs[(int(s), int(d))] = json.load(open(f))
    failed = set()
    for f in glob.glob(os.path.join(res, "table2", "seed*_dense*.failed")):
        s, d = os.path.basename(f)[4:-7].split("_dense")
        failed.add((int(s), int(d)))
    rows2, t2 = table2(runs, failed)
    load = open(os.path.join(res, "load.txt")).read().strip() if os.path.exists(os.path.join(res, "load.txt")) else ""
    md = ["## Table 1: mapping a deformed Colin27 (%d seeds, medians; %d vertices, %d tets; %s)" % (
        t1["seeds"], t1["vertices"], t1["tets"], t1["device"]), ""] + table1(t1s) + [
        "", "## Table 2: held-out Dice after registration (medians over seeds)", ""] + rows2 + [
        "", "Machine load (uptime at start and end):", "", "```", load, "```", ""]
    open(os.path.join(res, "paper.md"), "w").write("\n".join(md))
    json.dump({"table1": t1["median"], "table1_runs": t1["runs"],
               "table1_stronger_flows": [{"amplitude": t["amplitude"], "median": t["median"], "runs": t["runs"]} for t in t1s[1:]],
               "table2": t2,
               "paper": {"table1": PAPER_T1, "dice": dict(zip(NAMES, PAPER_DICE)), "registration_distortion": 0.03}},
              open(os.path.join(res, "paper.json"), "w"), indent=1)
    fig3(t1["fig3_log_vertex_ratio"], os.path.join(res, "fig3.png"))
    print("\n".join(md))


if __name__ == "__main__":
    main()
