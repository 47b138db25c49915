#!/usr/bin/env python3
"""Summarises bench/forces/run.sh: WORK/<force>[_incompressible]_seed<S>/demo.json -> OUT/forces.json
and OUT/forces.md (medians over the seeds; failed runs counted)."""
import glob
import json
import os
import re
import statistics
import sys


def main():
    work, out = sys.argv[1], sys.argv[2]
    groups = {}
    for d in sorted(glob.glob(os.path.join(work, "*_seed*"))):
        if not os.path.isdir(d):
            continue
        m = re.match(r"(\w+?)(_incompressible)?_seed(\d+)$", os.path.basename(d))
        if not m:
            continue
        key = (m.group(1), "incompressible" if m.group(2) else "demo")
        g = groups.setdefault(key, {"runs": [], "failed": []})
        path = os.path.join(d, "demo.json")
        if not os.path.isfile(path):
            g["failed"].append(int(m.group(3)))
            continue
        j = json.load(open(path))
        held = j["overlap"]["held_out"]
        g["runs"].append({
            "seed": int(m.group(3)),
            "names": [h["name"] for h in held],
            "dice": [h["dice_image_after"] for h in held],
            "bound": [h["dice_volume_bound"] for h in held],
            "landmark_regions": j["overlap"]["landmark_regions_mean_dice_image_after"],
            "tet": j["registration"]["tet_volume_ratio"]["mean_abs_dev"],
            "vertex": j["registration"]["vertex_volume_ratio"]["mean_abs_dev"],
            "seconds": j["timings_s"]["register"],
        })
    med = statistics.median
    rows, result = [], []
    names = None
    for (force, deformation), g in sorted(groups.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        r = g["runs"]
        if not r:
            continue
        names = r[0]["names"]
        k = len(names)
        s = {"force": force, "deformation": deformation, "runs": len(r), "failed_seeds": g["failed"],
             "dice": [med([x["dice"][i] for x in r]) for i in range(k)],
             "bound": [med([x["bound"][i] for x in r]) for i in range(k)],
             "landmark_regions": med([x["landmark_regions"] for x in r]),
             "tet": med([x["tet"] for x in r]), "vertex": med([x["vertex"] for x in r]),
             "seconds": med([x["seconds"] for x in r]), "per_seed": r}
        result.append(s)
        rows.append("| %s | %s | %s | %s | %.3f | %.2f %% / %.2f %% | %.1f | %d (%d) |" % (
            deformation, force, " | ".join("%.3f" % x for x in s["dice"]), " / ".join("%.3f" % x for x in s["bound"]),
            s["landmark_regions"], 100 * s["vertex"], 100 * s["tet"], s["seconds"], len(r), len(g["failed"])))
    if not result:
        sys.exit("forces: no runs found in " + work)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "forces.json"), "w") as f:
        json.dump({"held_out": names, "groups": result}, f, indent=1)
    head = ("| deformation | force | " + " | ".join(names) + " | volume bounds | landmark regions | "
            "vertex / tet abs(r-1) | registration s | runs (failed) |")
    md = ["## Dense registration forces: held-out Dice through the maps (medians over seeds)", "", head,
          "|" + "---|" * (7 + len(names)), *rows]
    with open(os.path.join(out, "forces.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
