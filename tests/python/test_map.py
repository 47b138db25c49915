"""One end-to-end run from Python: an image meshed, mapped to the ball, a second subject
registered to it (landmarks, template regions, moments + image force), sampled in the canonical
elements and compared."""
import numpy as np
import pytest

from conftest import ellipsoid


def test_map_to_ball_end_to_end(vpm, small_mesh, ball):
    out, report = ball
    assert isinstance(report, vpm.MapReport)
    assert report.final.inverted_tets == 0
    assert report.final.vertex_volume_ratio.mean_abs_dev < 0.02
    assert report.initial.vertex_volume_ratio.mean_abs_dev > report.final.vertex_volume_ratio.mean_abs_dev
    d = report.to_dict()
    assert d["final"]["inverted_tets"] == 0 and d["input"]["tets"] == small_mesh.num_tets
    assert d["final"]["vertex_volume_ratio"]["mean_abs_dev"] == pytest.approx(report.final.vertex_volume_ratio.mean_abs_dev)
    assert 0 < report.seconds < 600
    r = np.linalg.norm(out.vertices, axis=1)
    assert r.max() <= 1 + 1e-9
    initial, ireport = vpm.initial_map(small_mesh.copy())
    assert isinstance(ireport, vpm.InitialMapReport) and "boundary" in ireport.to_dict()
    assert np.linalg.norm(initial.vertices, axis=1).max() <= 1 + 1e-9


def labelled(vpm, data, affine):
    """The ellipsoid meshed with four 'regions' (octants of x and y) as atlas labels."""
    i, j, _ = np.meshgrid(*[np.arange(n) for n in data.shape], indexing="ij")
    atlas = ((i > data.shape[0] / 2) * 1 + (j > data.shape[1] / 2) * 2 + 1) * (data > 0)
    return vpm.mesh_image(data, labels=atlas.astype(np.float32), affine=affine, target_vertices=500)[0]


def test_register_landmarks_template_and_moments(vpm, image_array):
    data, affine = image_array
    t_ball, _ = vpm.map_to_ball(labelled(vpm, data, affine))
    data2, affine2 = ellipsoid(radii=(28.0, 25.0, 19.0))
    s_ball, _ = vpm.map_to_ball(labelled(vpm, data2, affine2))
    # landmarks as vertex ids and as coordinates
    inner = np.flatnonzero(np.linalg.norm(s_ball.vertices, axis=1) < 0.8)
    ids = inner[[0, len(inner) // 3, 2 * len(inner) // 3, -1]]
    moved = s_ball.vertices[ids] * 0.97
    reg, rep = vpm.register(s_ball, landmarks=ids, targets=moved)
    assert rep.landmark_rms_error < 1e-6 and rep.inverted_tets == 0
    assert np.allclose(reg.vertices[ids], moved, atol=1e-5)
    # template: region centroids
    reg, rep = vpm.register(s_ball, template=t_ball)
    assert rep.landmarks == 4 and rep.landmark_rms_error < 1e-6
    assert "tet_volume_ratio" in reg.cell_data
    # presets: 'landmarks' is the registration above; a preset's iterations give way to
    # dense_iterations=; an unknown name is a ValueError
    same, _ = vpm.register(s_ball, template=t_ball, preset="landmarks")
    assert np.array_equal(same.vertices, reg.vertices)
    one, rep1 = vpm.register(s_ball, template=t_ball, preset="accurate", dense_iterations=1)
    assert rep1.inverted_tets == 0 and not np.array_equal(one.vertices, reg.vertices)
    with pytest.raises(ValueError, match="unknown preset 'fast'"):
        vpm.register(s_ball, template=t_ball, preset="fast")
    # no labels: the moments' affine and the image force
    bare = s_ball.copy()
    bare = vpm.Mesh(bare.vertices, bare.tets, point_data={"original_position": bare.point_data["original_position"]})
    lines = []
    reg, rep = vpm.register(bare, template=t_ball, template_landmarks="moments", dense_iterations=3,
                            dense_force="image", image=vpm.Image(data2, affine2), template_image=(vpm.Image(data, affine)),
                            progress=lines.append)
    assert rep.landmarks >= 20 and rep.inverted_tets == 0
    assert len(lines) >= 1  # one line per dense iteration
    # the image refinement after them moves the vertices further; it needs an image force
    refined, rep2 = vpm.register(bare, template=t_ball, template_landmarks="moments", dense_iterations=3,
                                 dense_force="image", dense_refine=20, image=vpm.Image(data2, affine2),
                                 template_image=vpm.Image(data, affine))
    assert rep2.inverted_tets == 0 and not np.array_equal(refined.vertices, reg.vertices)
    with pytest.raises(ValueError, match="needs dense_force='image' or 'both'"):
        vpm.register(s_ball, template=t_ball, dense_iterations=1, dense_refine=10)
    with pytest.raises(ValueError, match="needs atlas labels"):
        vpm.register(bare, template=t_ball, template_landmarks="moments", dense_iterations=1, dense_force="labels")


def test_sample_and_compare(vpm, ball, image_array, tmp_path):
    out, _ = ball
    data, affine = image_array
    el = vpm.elements(level=1, shells=2, samples=8)
    assert len(el) == 160 and el.samples.shape == (160 * 8, 3)
    rng, rng_t1 = np.random.default_rng(3), np.random.default_rng(4)
    tables = []
    for s in range(4):
        pet = data * (1 + 0.02 * rng.standard_normal(data.shape)).astype(np.float32)
        t1w = data * (1 + 0.02 * rng_t1.standard_normal(data.shape)).astype(np.float32)
        if s == 3:
            pet[data.shape[0] // 2:] *= 0.5  # the patient: half the brain hypometabolic
        tables.append(vpm.sample(out, {"pet": vpm.Image(pet, affine), "t1w": vpm.Image(t1w, affine)}, elements=el,
                                 subject=f"sub-{s}"))
    f = tables[0].features["pet"]
    assert f["mean"].shape == (160,) and (f["count"] > 0).sum() > 100
    c = vpm.compare(tables[:3], tables[3], "pet", threshold=3, min_cluster=2, sign="hypo")
    assert c.z.shape == (160,) and np.nanmin(c.z) < -3
    assert c.clusters and all(k["sign"] == -1 for k in c.clusters)
    assert c.to_dict()["clusters"] == c.clusters
    # the spread shrunk across adjacent elements: the same means, steadier spreads
    s = vpm.compare(tables[:3], tables[3], "pet", threshold=3, min_cluster=2, sign="hypo", shrink=1.0)
    assert np.allclose(s.reference_mean, c.reference_mean, equal_nan=True)
    ok = np.isfinite(c.reference_std) & np.isfinite(s.reference_std)
    assert ok.sum() > 100 and np.ptp(s.reference_std[ok]) < np.ptp(c.reference_std[ok])
    # the relative extent only trims the foci the hysteresis found: the same foci, no element added
    h = vpm.compare(tables[:3], tables[3], "pet", threshold=3, min_cluster=2, extend=2, sign="hypo")
    r = vpm.compare(tables[:3], tables[3], "pet", threshold=3, min_cluster=2, extend=2, sign="hypo",
                    relative_extent=0.9)
    assert len(r.clusters) == len(h.clusters) and ((r.cluster > 0) <= (h.cluster > 0)).all()
    assert (r.cluster > 0).sum() < (h.cluster > 0).sum()
    with pytest.raises(ValueError, match="relative_extent"):
        vpm.compare(tables[:3], tables[3], "pet", relative_extent=1.5)
    # TFCE: each focus holds an element at the level; none reaches an unreachable one
    t = vpm.compare(tables[:3], tables[3], "pet", extend=2, sign="hypo", tfce_level=1.0)
    assert t.clusters and all(c["peak_tfce"] >= 1.0 and c["peak_z"] < 0 for c in t.clusters)
    assert not vpm.compare(tables[:3], tables[3], "pet", extend=2, sign="hypo", tfce_level=1e9).clusters
    with pytest.raises(ValueError, match="tfce_level"):
        vpm.compare(tables[:3], tables[3], "pet", tfce_level=-1)
    # every option's range is the library's (compare_option_error), worded with the keywords
    with pytest.raises(ValueError, match="^fdr: "):
        vpm.compare(tables[:3], tables[3], "pet", fdr=1.0)
    with pytest.raises(ValueError, match="^threshold: "):
        vpm.compare(tables[:3], tables[3], "pet", threshold=-1)
    # covariates from a participants table: the reference a linear model of age, the patient
    # compared with its own prediction (reference_mean then differs from the normals' mean)
    table = tmp_path / "participants.tsv"
    table.write_text("participant_id\tage\nsub-0\t30\nsub-1\t50\nsub-2\t70\nsub-3\t40\n")
    a = vpm.compare(tables[:3], tables[3], "pet", covariates=["age"], participants=str(table))
    assert a.z.shape == (160,) and a.summary["clusters"] == a.clusters
    both = np.isfinite(a.reference_mean) & np.isfinite(c.reference_mean)
    assert both.sum() > 100 and not np.allclose(a.reference_mean[both], c.reference_mean[both])
    with pytest.raises(ValueError, match="give both"):
        vpm.compare(tables[:3], tables[3], "pet", covariates=["age"])
    with pytest.raises(ValueError, match="no column 'weight'"):
        vpm.compare(tables[:3], tables[3], "pet", covariates=["weight"], participants=str(table))
    # an image covariate: each element's reference models the subjects' own t1w there, the
    # patient's expected value is its own prediction
    i = vpm.compare(tables[:3], tables[3], "pet", image_covariate="t1w")
    both = np.isfinite(i.reference_mean) & np.isfinite(c.reference_mean)
    assert both.sum() > 100 and not np.allclose(i.reference_mean[both], c.reference_mean[both])
    with pytest.raises(ValueError, match="is the feature compared itself"):
        vpm.compare(tables[:3], tables[3], "pet", image_covariate="pet")
    with pytest.raises(ValueError, match="no feature 'fa'"):
        vpm.compare(tables[:3], tables[3], "pet", image_covariate="fa")
    zimg = vpm.to_image(out, el, np.nan_to_num(c.z), vpm.Image(data, affine))
    assert zimg.shape == data.shape and zimg.data.min() < -3
    native = vpm.to_native(out, np.zeros((1, 3)))
    assert native.shape == (1, 3) and np.isfinite(native).all()
