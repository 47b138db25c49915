#!/usr/bin/env python3
"""Compares two output folders of vpm (e.g. two `vpm demo --out` runs before and after a change):
.vtu/.csv/.tsv files byte for byte, .json reports equal once timing keys are removed.
Prints one line per difference and a count; exits 1 when anything differs.
Usage: compare_outputs.py DIR_BEFORE DIR_AFTER
"""
import json, sys, os, filecmp
a, b = sys.argv[1], sys.argv[2]
def strip(o):
    if isinstance(o, dict):
        return {k: strip(v) for k, v in o.items() if not (k.startswith('timings') or k in ('seconds','total_s','time_s','device') or k.endswith('_s') or k.endswith('_seconds'))}
    if isinstance(o, list): return [strip(x) for x in o]
    return o
bad = 0
for f in sorted(os.listdir(a)):
    pa, pb = os.path.join(a, f), os.path.join(b, f)
    if not os.path.exists(pb): print('missing', f); bad += 1; continue
    if f.endswith('.json'):
        ja, jb = strip(json.load(open(pa))), strip(json.load(open(pb)))
        if ja != jb: print('json differs', f); bad += 1
    elif not filecmp.cmp(pa, pb, shallow=False): print('differs', f); bad += 1
print('compared', len(os.listdir(a)), 'files,', bad, 'differences')
sys.exit(1 if bad else 0)
