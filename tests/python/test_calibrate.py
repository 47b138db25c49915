"""The foci rule set by the normals from Python: vpm.calibrate (each normal left out in turn) and
vpm.compare(calibration=...), against `vpm calibrate` and `vpm compare --min-cluster-from`."""
import json
import subprocess

import numpy as np
import pytest


@pytest.fixture(scope="module")
def cohort(vpm, ball, image_array, tmp_path_factory):
    """Six normals (2 % voxel noise) and a patient with a hypometabolic half, sampled in small
    elements; each table also written to a file."""
    out, _ = ball
    data, affine = image_array
    el = vpm.elements(level=1, shells=2, samples=8)
    rng = np.random.default_rng(11)
    folder = tmp_path_factory.mktemp("calibrate")
    tables, paths = [], []
    for s in range(7):
        pet = data * (1 + 0.02 * rng.standard_normal(data.shape)).astype(np.float32)
        if s == 6:
            pet[data.shape[0] // 2:] *= 0.6
        t = vpm.sample(out, {"pet": vpm.Image(pet, affine)}, elements=el, subject=f"sub-{s}")
        path = folder / f"sub-{s}.h5"
        t.write(str(path))
        tables.append(t)
        paths.append(str(path))
    return tables, paths, folder


def test_calibrate_and_compare_with_it(vpm, cohort):
    tables, _, _ = cohort
    normals, patient = tables[:6], tables[6]
    cal = vpm.calibrate(normals, "pet", sign="hypo", extend=2, peak="auto", rate=8)
    assert cal["normals"] == 6 and sorted(n["normal"] for n in cal["per_normal"]) == [f"sub-{s}" for s in range(6)]
    # not compare's default size, so that a calibration left unapplied shows
    assert cal["min_cluster"] not in (0, 3) and cal["calibrate_peak"] is True and cal["peak"] > 3
    # the calibrated size is the smallest whose false clusters stay at or under the rate
    curve = {r["min_cluster"]: r["per_10_normals"] for r in cal["curve"]}
    assert curve[cal["min_cluster"]] <= 8 and (cal["min_cluster"] == 1 or curve[cal["min_cluster"] - 1] > 8)
    c = vpm.compare(normals, patient, "pet", sign="hypo", extend=2, calibration=cal)
    assert c.summary["min_cluster"] == cal["min_cluster"] and c.summary["peak"] == cal["peak"]
    # the same foci as the calibrated rule given by hand, now with family-wise p-values
    by_hand = vpm.compare(normals, patient, "pet", sign="hypo", extend=2, min_cluster=cal["min_cluster"],
                          peak=cal["peak"])
    assert np.array_equal(c.cluster, by_hand.cluster) and c.clusters
    assert all("p_family" not in k for k in by_hand.clusters)
    assert all(1 / 7 <= k["p_family"] <= 1 for k in c.clusters)
    # the hypometabolic half lies beyond every normal left out: the least p-value there is
    assert min(k["p_family"] for k in c.clusters) == pytest.approx(1 / 7)
    # TFCE: the level calibrated, applied by the calibration
    t = vpm.calibrate(normals, "pet", sign="hypo", extend=2, tfce=True)
    assert t["tfce_level"] > 0
    ct = vpm.compare(normals, patient, "pet", sign="hypo", extend=2, calibration=t)
    assert ct.summary["tfce_level"] == t["tfce_level"] and all(k["peak_tfce"] >= t["tfce_level"] for k in ct.clusters)


def test_calibration_refused_where_it_does_not_hold(vpm, cohort, tmp_path):
    tables, _, _ = cohort
    normals, patient = tables[:6], tables[6]
    cal = vpm.calibrate(normals, "pet", sign="hypo")
    with pytest.raises(ValueError, match="calibrated on other normals"):
        vpm.compare(normals[:5], patient, "pet", sign="hypo", calibration=cal)
    with pytest.raises(ValueError, match="threshold"):
        vpm.compare(normals, patient, "pet", sign="hypo", threshold=2.5, calibration=cal)
    with pytest.raises(ValueError, match="min_cluster: the calibration sets it"):
        vpm.compare(normals, patient, "pet", sign="hypo", min_cluster=4, calibration=cal)
    with pytest.raises(ValueError, match="at least 4"):
        vpm.calibrate(normals[:3], "pet")
    with pytest.raises(ValueError, match="min_cluster: not taken"):
        vpm.calibrate(normals, "pet", min_cluster=3)
    with pytest.raises(ValueError, match="peak"):
        vpm.calibrate(normals, "pet", peak="often")
    with pytest.raises(ValueError, match="tfce and peak"):
        vpm.calibrate(normals, "pet", peak="auto", tfce=True)
    with pytest.raises(ValueError, match="rate"):
        vpm.calibrate(normals, "pet", rate=-1)
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]")
    with pytest.raises(ValueError, match="bad.json: not a calibration"):
        vpm.compare(normals, patient, "pet", calibration=str(bad))
    with pytest.raises(ValueError, match="absent.json: No such file"):
        vpm.compare(normals, patient, "pet", calibration=str(tmp_path / "absent.json"))


def test_calibration_the_same_as_the_command_line(vpm, cli, cohort):
    _, paths, folder = cohort
    normals, patient = paths[:6], paths[6]
    cal = vpm.calibrate(normals, "pet", sign="hypo", extend=2, relative_extent=0.2, peak="auto")
    out = folder / "cal.json"
    r = subprocess.run([cli, "calibrate", "--normals", ",".join(normals), "--feature", "pet", "--sign", "hypo",
                        "--extend", "2", "--relative-extent", "0.2", "--peak", "auto", "-o", str(out)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    made = json.loads(out.read_text())
    for key in ("min_cluster", "peak", "curve", "sizes", "per_normal"):
        assert made[key] == cal[key], key
    # the command line's file applies from Python as its own dict does
    a = vpm.compare(normals, patient, "pet", sign="hypo", extend=2, relative_extent=0.2, calibration=str(out))
    b = vpm.compare(normals, patient, "pet", sign="hypo", extend=2, relative_extent=0.2, calibration=cal)
    assert np.array_equal(a.cluster, b.cluster) and a.clusters == b.clusters
    tsv = folder / "cmp.tsv"
    r = subprocess.run([cli, "compare", "--normals", ",".join(normals), "--patient", patient, "--feature", "pet",
                        "--sign", "hypo", "--extend", "2", "--relative-extent", "0.2", "--min-cluster-from", str(out),
                        "-o", str(tsv)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    written = json.loads((folder / "cmp.json").read_text())
    assert written["options"]["min_cluster"] == cal["min_cluster"] and written["options"]["peak"] == cal["peak"]
    assert [k["p_family"] for k in written["result"]["clusters"]] == [k["p_family"] for k in a.clusters]
