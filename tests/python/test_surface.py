"""Closed surfaces to the sphere from Python (vpm.map_to_sphere, vpm.read_surface,
vpm.write_surface), against the same checks as `vpm map SURFACE`."""
import numpy as np
import pytest


def bumpy_ellipsoid(vpm, tmp_path):
    """An ellipsoid 1.8 : 1 : 0.6 with a bump, from a unit sphere triangulated by vpm's mesher's
    boundary: the vertices of a FreeSurfer-format round trip."""
    t = np.linspace(0, np.pi, 24)[1:-1]
    p = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    tt, pp = np.meshgrid(t, p, indexing="ij")
    pts = np.stack([np.sin(tt) * np.cos(pp), np.sin(tt) * np.sin(pp), np.cos(tt)], -1).reshape(-1, 3)
    pts = np.vstack([[0, 0, 1], pts, [0, 0, -1]])
    faces = []
    rings, per = len(t), len(p)
    idx = lambda r, k: 1 + r * per + k % per  # noqa: E731
    for k in range(per):
        faces.append([0, idx(0, k), idx(0, k + 1)])
        faces.append([len(pts) - 1, idx(rings - 1, k + 1), idx(rings - 1, k)])
        for r in range(rings - 1):
            faces.append([idx(r, k), idx(r + 1, k), idx(r + 1, k + 1)])
            faces.append([idx(r, k), idx(r + 1, k + 1), idx(r, k + 1)])
    g = 1 + 0.4 * np.exp(-np.sum((pts - [0.6, 0, 0.8]) ** 2, axis=1) / 0.15)
    v = pts * [1.8, 1.0, 0.6] * g[:, None]
    return v, np.array(faces)


def test_map_to_sphere_keeps_face_areas(vpm, tmp_path):
    v, f = bumpy_ellipsoid(vpm, tmp_path)
    vpm.write_surface(tmp_path / "lh.white", v, f)
    v32, f2 = vpm.read_surface(tmp_path / "lh.white")  # FreeSurfer: float32 coordinates
    assert np.array_equal(f2, f) and np.allclose(v32, v, atol=1e-5)
    sphere, report = vpm.map_to_sphere(v, f)
    assert isinstance(report, vpm.SurfaceMapReport)
    assert sphere.shape == v.shape
    assert np.abs(np.linalg.norm(sphere, axis=1) - 1).max() < 1e-12
    assert report.final.flipped_faces == 0
    assert report.final.face_area_ratio.mean_abs_dev <= 0.005 < report.initial.face_area_ratio.mean_abs_dev
    assert report.converged
    d = report.to_dict()
    assert d["final"]["face_area_ratio"]["mean_abs_dev"] == pytest.approx(report.final.face_area_ratio.mean_abs_dev)
    # the areas measured here agree: chord triangles against the input's, normalised
    def areas(x):
        a = 0.5 * np.linalg.norm(np.cross(x[f[:, 1]] - x[f[:, 0]], x[f[:, 2]] - x[f[:, 0]]), axis=1)
        return a / a.sum()
    assert np.mean(np.abs(areas(sphere) / areas(v) - 1)) == pytest.approx(report.final.face_area_ratio.mean_abs_dev)


def test_map_to_sphere_refuses_open_surfaces(vpm, tmp_path):
    v, f = bumpy_ellipsoid(vpm, tmp_path)
    with pytest.raises(ValueError, match="holes"):
        vpm.map_to_sphere(v, f[1:])
    with pytest.raises(ValueError, match="out of range"):
        vpm.map_to_sphere(v, np.vstack([f, [[0, 1, len(v)]]]))


def test_gifti_against_nibabel(vpm, tmp_path):
    """GIfTI surfaces written by nibabel (each encoding) read by vpm, and vpm's read by nibabel."""
    nib = pytest.importorskip("nibabel")
    from nibabel.gifti import GiftiDataArray, GiftiImage
    v, f = bumpy_ellipsoid(vpm, tmp_path)
    v = v.astype(np.float32)
    for enc in ("ASCII", "GIFTI_ENCODING_B64BIN", "GIFTI_ENCODING_B64GZ"):
        img = GiftiImage(darrays=[GiftiDataArray(v, intent="NIFTI_INTENT_POINTSET", encoding=enc),
                                  GiftiDataArray(f.astype(np.int32), intent="NIFTI_INTENT_TRIANGLE", encoding=enc)])
        nib.save(img, tmp_path / f"{enc}.surf.gii")
        v2, f2 = vpm.read_surface(tmp_path / f"{enc}.surf.gii")
        assert np.array_equal(f2, f), enc
        if enc == "ASCII":  # nibabel writes ASCII values with 6 decimals
            assert np.abs(v2 - v).max() <= 1e-6
        else:
            assert np.array_equal(v2, v.astype(np.float64)), enc
    # column-major float64 points and uint16 triangles, as other writers may store them
    img = GiftiImage(darrays=[
        GiftiDataArray(v.astype(np.float64), intent="NIFTI_INTENT_POINTSET", encoding="GIFTI_ENCODING_B64GZ",
                       ordering="ColumnMajorOrder"),
        GiftiDataArray(f.astype(np.uint16), intent="NIFTI_INTENT_TRIANGLE", encoding="GIFTI_ENCODING_B64BIN",
                       ordering="ColumnMajorOrder")])
    nib.save(img, tmp_path / "column.surf.gii")
    v2, f2 = vpm.read_surface(tmp_path / "column.surf.gii")
    assert np.array_equal(v2, v.astype(np.float64)) and np.array_equal(f2, f)
    vpm.write_surface(tmp_path / "vpm.surf.gii", v, f)
    g = nib.load(tmp_path / "vpm.surf.gii")
    assert np.array_equal(g.agg_data("NIFTI_INTENT_POINTSET"), v)
    assert np.array_equal(g.agg_data("NIFTI_INTENT_TRIANGLE"), f)


def test_map_to_disk(vpm):
    """A bumpy disk (polar grid) to the unit disk: areas kept, boundary on the circle, z = 0."""
    rings, sectors = 12, 48
    pts = [[0.0, 0.0]]
    for i in range(1, rings + 1):
        for j in range(sectors):
            a = 2 * np.pi * (j + 0.5 * (i % 2)) / sectors
            pts.append([i / rings * np.cos(a), i / rings * np.sin(a)])
    pts = np.array(pts)
    idx = lambda i, j: 1 + (i - 1) * sectors + j % sectors  # noqa: E731
    faces = [[0, idx(1, j), idx(1, j + 1)] for j in range(sectors)]
    for i in range(1, rings):
        for j in range(sectors):
            a, b = idx(i, j), idx(i, j + 1)
            if i % 2:
                c, d = idx(i + 1, j + 1), idx(i + 1, j + 2)
                faces += [[a, c, b], [b, c, d]]
            else:
                c, d = idx(i + 1, j), idx(i + 1, j + 1)
                faces += [[a, c, d], [a, d, b]]
    z = 0.5 * np.exp(-((pts[:, 0] - 0.3) ** 2 + pts[:, 1] ** 2) / 0.08)
    v = np.column_stack([pts, z])
    disk, report = vpm.map_to_disk(v, np.array(faces))
    assert report.to_dict()["domain"] == "disk"
    assert report.final.flipped_faces == 0
    assert report.final.face_area_ratio.mean_abs_dev <= 0.005 < report.initial.face_area_ratio.mean_abs_dev
    assert np.all(disk[:, 2] == 0) and np.linalg.norm(disk[:, :2], axis=1).max() <= 1 + 1e-12
    assert np.array_equal(report.faces, faces) and report.added.shape == (0, 2)
    # cut by a line (centroids x < 0.55): the zigzag leaves ears, split before the map; the
    # points gain a row per halved edge, report.faces index them
    keep = [f for f in faces if v[f, 0].mean() < 0.55]
    used = np.unique(keep)
    cut_v, cut_f = v[used], np.searchsorted(used, keep)
    cut, cut_report = vpm.map_to_disk(cut_v, cut_f)
    d = cut_report.to_dict()["disk_map"]
    assert d["ears"] == d["split_edges"] == len(cut_report.added) == len(cut) - len(cut_v) > 0
    assert cut_report.faces.shape == (len(cut_f) + 2 * d["split_edges"], 3) and cut_report.faces.max() == len(cut) - 1
    assert cut_report.final.face_area_ratio.min > 0.8 and cut_report.final.flipped_faces == 0
    with pytest.raises(ValueError, match="closed"):
        vpm.map_to_disk(*bumpy_ellipsoid(vpm, None))
    # registered in the disk: landmarks (vertex ids) onto targets turned about the centre by up
    # to 0.15 rad, exact, no face flipped, the boundary on the circle
    inner = np.where(np.linalg.norm(disk[:, :2], axis=1) < 0.8)[0][::25]
    turn = 0.15 * np.sin(np.pi * np.linalg.norm(disk[inner, :2], axis=1))
    c, s = np.cos(turn), np.sin(turn)
    targets = np.column_stack([c * disk[inner, 0] - s * disk[inner, 1], s * disk[inner, 0] + c * disk[inner, 1], 0 * c])
    reg, rep = vpm.register_in_disk(disk, np.array(faces), inner, targets)
    assert rep.to_dict()["landmark_max_error"] <= 1e-10
    assert rep.final.flipped_faces == 0
    assert np.linalg.norm(reg[:, :2], axis=1).max() <= 1 + 1e-12
    with pytest.raises(ValueError, match="strictly inside"):
        vpm.register_in_disk(disk, np.array(faces), inner[:2], np.array([[1.0, 0, 0], [0, 0.5, 0]]))
    # dense: a template whose scalar is the subject's turned by the same swirl, recovered
    r = np.linalg.norm(disk[:, :2], axis=1)
    turn = 0.15 * np.sin(np.pi * r)
    c, s = np.cos(turn), np.sin(turn)
    truth = np.column_stack([c * disk[:, 0] - s * disk[:, 1], s * disk[:, 0] + c * disk[:, 1], 0 * c])
    values = np.sin(disk[:, :2] @ np.array([[3, 1], [-2, 4], [5, 2]]).T + [0.2, 1.1, 2.3]).sum(1)
    dense, rep = vpm.register_in_disk(disk, np.array(faces), values=values, template=(truth, np.array(faces), values))
    d = rep.to_dict()
    assert d["match"]["correlation_after"] > 0.99 and d["match"]["correlation_after"] > d["match"]["correlation_before"]
    assert np.linalg.norm(dense - truth, axis=1).mean() < 0.5 * np.linalg.norm(disk - truth, axis=1).mean()
    assert rep.final.flipped_faces == 0
    flows = [vpm.register_in_disk(disk, np.array(faces), values=values, template=(truth, np.array(faces), values), restore=False,
                                  **d)[0] for d in ({"device": "host"}, {})]
    assert np.abs(flows[0] - flows[1]).max() < 1e-9  # the host and the module's device (PoCL in CI) alike
    with pytest.raises(ValueError, match="give both"):
        vpm.register_in_disk(disk, np.array(faces), values=values)


def test_overlays_against_nibabel(vpm, tmp_path):
    """FreeSurfer per-vertex files and GIfTI shape files written by nibabel, read by vpm."""
    nib = pytest.importorskip("nibabel")
    from nibabel.freesurfer import write_morph_data
    from nibabel.gifti import GiftiDataArray, GiftiImage
    vals = np.sin(np.arange(500) / 7.0).astype(np.float32)
    write_morph_data(str(tmp_path / "lh.curv"), vals)
    assert np.array_equal(vpm.read_overlay(tmp_path / "lh.curv"), vals.astype(np.float64))
    img = GiftiImage(darrays=[GiftiDataArray(vals, intent="NIFTI_INTENT_SHAPE", encoding="GIFTI_ENCODING_B64GZ")])
    nib.save(img, tmp_path / "lh.thickness.shape.gii")
    assert np.array_equal(vpm.read_overlay(tmp_path / "lh.thickness.shape.gii"), vals.astype(np.float64))
    with pytest.raises(ValueError, match="not a FreeSurfer per-vertex file"):
        (tmp_path / "bad.curv").write_bytes(b"\x00" * 40)
        vpm.read_overlay(tmp_path / "bad.curv")


def test_register_on_sphere(vpm, tmp_path):
    """Landmarks on the sphere moved onto targets: exact, areas kept, the identity on itself."""
    v, f = bumpy_ellipsoid(vpm, tmp_path)
    sphere, _ = vpm.map_to_sphere(v, f)
    rng = np.random.default_rng(3)
    ids = rng.choice(len(sphere), 10, replace=False)
    src = sphere[ids]
    step = rng.normal(size=(10, 3))
    step -= (step * src).sum(1)[:, None] * src
    tgt = src + 0.05 * step / np.linalg.norm(step, axis=1)[:, None]
    tgt /= np.linalg.norm(tgt, axis=1)[:, None]
    reg, report = vpm.register_on_sphere(sphere, f, src, tgt)
    assert np.allclose(np.linalg.norm(reg, axis=1), 1, atol=1e-12)
    d = report.to_dict()
    assert d["landmark_max_error"] <= 1e-10
    assert report.final.flipped_faces == 0
    assert report.final.face_area_ratio.mean_abs_dev <= report.initial.face_area_ratio.mean_abs_dev
    by_id, _ = vpm.register_on_sphere(sphere, f, ids, tgt)  # landmarks as vertex ids
    assert np.array_equal(by_id, reg)
    # the flow on the host and on the module's device (OpenCL where there is one): round-off apart
    flows = [vpm.register_on_sphere(sphere, f, src, tgt, restore=False, **d)[0] for d in ({"device": "host"}, {})]
    assert np.abs(flows[0] - flows[1]).max() < 1e-9
    with pytest.raises(ValueError, match="no-such-device"):
        vpm.register_on_sphere(sphere, f, src, tgt, device="no-such-device")
    with pytest.raises(ValueError, match="vertex id out of range"):
        vpm.register_on_sphere(sphere, f, np.array([0, len(sphere)]), tgt[:2])
    same, _ = vpm.register_on_sphere(sphere, f, src, src)
    assert np.abs(same - sphere).max() <= 1e-12
    with pytest.raises(ValueError, match="not on the unit sphere"):
        vpm.register_on_sphere(2 * sphere, f, src, tgt)


def test_dense_register_on_sphere(vpm, tmp_path):
    """A scalar's rotation recovered by the dense registration onto a template (the same surface
    rotated on the sphere, its scalar carried along); locate_on_sphere against the vertices."""
    v, f = bumpy_ellipsoid(vpm, tmp_path)
    sphere, _ = vpm.map_to_sphere(v, f)
    h = vpm.mean_curvature(2 * sphere, f)  # the sphere map's points on a sphere of radius 2
    assert abs(np.median(h) - 0.5) < 0.02
    faces_at, bary = vpm.locate_on_sphere(sphere, f, sphere[:50] * 3.0)  # any length: a direction
    rebuilt = (sphere[f[faces_at]] * bary[:, :, None]).sum(1)
    assert np.allclose(rebuilt, sphere[:50], atol=1e-12)
    c, s = np.cos(0.2), np.sin(0.2)
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    waves = np.array([[3, 0, 1, 0.2], [0, 4, -2, 1.1], [-2, 1, 5, 2.3], [5, -4, 0, 0.4], [1, 6, 3, 1.7]])
    values = np.sin(sphere @ waves[:, :3].T + waves[:, 3]).sum(1)  # plane waves crossing everywhere
    truth = sphere @ rot.T
    reg, report = vpm.register_on_sphere(sphere, f, values=values, template=(truth, f, values))
    d = report.to_dict()
    assert d["match"]["correlation_after"] > 0.99 > d["match"]["correlation_before"]
    angle = lambda a, b: np.arccos(np.clip((a * b).sum(1), -1, 1)).mean()  # noqa: E731
    assert angle(reg, truth) < 0.35 * angle(sphere, truth)
    assert report.final.flipped_faces == 0
    with pytest.raises(ValueError, match="give both"):
        vpm.register_on_sphere(sphere, f, values=values)
    with pytest.raises(ValueError, match="one per vertex"):
        vpm.register_on_sphere(sphere, f, values=values[:5], template=(truth, f, values))
