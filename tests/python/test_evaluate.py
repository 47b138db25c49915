"""The foci scorer of the cohort benchmarks (bench/cohort/evaluate.py score): voxel overlap, foci
found, false-positive clusters (26-connected pieces of the detection touching no planted focus)
and false foci (the method's own cluster ids touching none), on masks made by hand."""
import os
import sys

import numpy as np

from conftest import SOURCE

sys.path.insert(0, os.path.join(SOURCE, "bench", "cohort"))
import evaluate  # noqa: E402


def test_a_focus_in_pieces_is_one_focus():
    truth = np.zeros((30, 30, 30), dtype=np.uint8)
    truth[5:10, 5:10, 5:10] = 1    # planted focus 1: 125 voxels
    truth[20:24, 20:24, 20:24] = 2  # planted focus 2: missed
    det = np.zeros(truth.shape, dtype=np.float32)
    det[6:11, 6:11, 6:11] = 1   # focus 1 over planted 1 (64 of its 125 voxels inside) ...
    det[14:16, 5:7, 5:7] = 1    # ... and a piece of it apart, touching nothing planted
    det[5:7, 20:23, 5:7] = 2    # focus 2: false, in two pieces
    det[5:7, 25:27, 5:7] = 2
    det[25:27, 5:7, 25:27] = 3  # focus 3: false
    s = evaluate.score(det, truth)
    assert s["foci_found"] == 1 and s["foci_planted"] == 2
    assert s["false_positive_clusters"] == 4 and s["false_foci"] == 2
    detected = 125 + 8 + 12 + 8 + 8
    assert s["counts"] == {"intersection": 64, "detected": detected, "truth": 125 + 64,
                           "union": detected + 125 + 64 - 64}
    assert s["precision"] == 64 / detected
    # a foci-free patient: every focus false; the summary sums them
    empty = evaluate.score(det, np.zeros_like(truth))
    assert empty["false_foci"] == 3 and empty["false_positive_clusters"] == 5
    summary = evaluate.summarise([s, empty])
    assert summary["false_foci"] == 5 and summary["false_positive_clusters"] == 9
    assert summary["foci_free_patients"] == 1 and summary["false_clusters_in_foci_free"] == 5
