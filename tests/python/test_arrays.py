"""NumPy arrays in and out of vpm: views of the library's memory, no copies where the layout
allows, one copy into the library's layout otherwise."""
import numpy as np
import pytest


def address(a):
    return a.__array_interface__["data"][0]


def test_mesh_views_share_the_mesh_memory(vpm, small_mesh):
    m = small_mesh.copy()
    v1, v2 = m.vertices, m.vertices
    assert v1.dtype == np.float64 and v1.shape == (m.num_vertices, 3) and v1.flags.c_contiguous
    assert m.tets.dtype == np.int32 and m.tets.shape == (m.num_tets, 4)
    assert address(v1) == address(v2)  # the same memory each time: a view, not a copy
    v1[0] = [1.5, 2.5, 3.5]
    assert np.array_equal(m.vertices[0], [1.5, 2.5, 3.5])  # writes reach the mesh
    assert np.shares_memory(m.vertices, v2)
    m2 = m.copy()
    assert not np.shares_memory(m2.vertices, m.vertices)


def test_arrays_of_a_mesh_go_back_in_without_a_copy(vpm, small_mesh):
    # validation turns negatively oriented tets in place: visible in the caller's arrays only when
    # vpm worked on the same memory
    m = small_mesh.copy()
    m.tets[0, [0, 1]] = m.tets[0, [1, 0]]
    own = m.tets.copy()
    vpm.initial_map(m.vertices, m.tets, device="host")  # the mesh's own arrays: no copy
    assert not np.array_equal(m.tets[0], own[0])         # turned back in place
    foreign_v, foreign_t = np.array(small_mesh.vertices), np.array(small_mesh.tets)
    foreign_t[0, [0, 1]] = foreign_t[0, [1, 0]]
    before = foreign_t.copy()
    vpm.initial_map(foreign_v, foreign_t, device="host")  # arrays made elsewhere: copied once
    assert np.array_equal(foreign_t, before)


def test_addresses_of_the_mesh_vpm_works_on(vpm, small_mesh):
    m = small_mesh.copy()
    v, t = m.vertices, m.tets
    assert vpm._vpm._mesh_addresses(v, t) == (address(v), address(t))        # the mesh's own arrays
    assert vpm._vpm._mesh_addresses(m) == (address(v), address(t))           # the mesh itself
    fv, ft = np.array(v), np.array(t)
    assert vpm._vpm._mesh_addresses(fv, ft)[0] != address(fv)                 # copied once


def test_outputs_are_views_owned_by_their_mesh(vpm, small_mesh, ball):
    out, report = ball
    v = out.vertices
    assert v.base is not None and address(v) == address(out.vertices)
    n = small_mesh.num_vertices
    assert np.allclose(out.point_data["original_position"][:n], small_mesh.vertices)
    r = out.cell_data["tet_volume_ratio"]
    assert r.shape == (out.num_tets,) and np.shares_memory(r, out.cell_data["tet_volume_ratio"])
    del out  # the views keep the mesh alive
    assert np.isfinite(v).all() and np.linalg.norm(v, axis=1).max() <= 1 + 1e-9


def test_mesh_from_arrays_and_fields(vpm, small_mesh):
    m = vpm.Mesh(small_mesh.vertices.tolist(), small_mesh.tets.astype(np.int64),
                 cell_data={"label": np.arange(small_mesh.num_tets) % 3})
    assert m.num_vertices == small_mesh.num_vertices
    assert np.array_equal(m.cell_data["label"], np.arange(small_mesh.num_tets) % 3)
    m.set_point_field("f", np.ones((m.num_vertices, 2)))
    assert m.point_data["f"].shape == (m.num_vertices, 2)
    with pytest.raises(ValueError, match="rows for"):
        m.set_cell_field("bad", np.ones(3))
    with pytest.raises(ValueError, match=r"expected an \(n, 3\) array"):
        vpm.Mesh(np.zeros((4, 2)), small_mesh.tets)
    with pytest.raises(ValueError, match="out of range"):
        vpm.Mesh(np.zeros((3, 3)), [[0, 1, 2, 3]])


def test_read_write_round_trip(vpm, ball, tmp_path):
    out, _ = ball
    p = str(tmp_path / "ball.vtu")
    vpm.write_mesh(p, out)
    back = vpm.read_mesh(p)
    assert np.array_equal(back.vertices, out.vertices) and np.array_equal(back.tets, out.tets)
    assert set(back.point_data) == set(out.point_data)


def test_image_views(vpm, image_array):
    data, affine = image_array
    img = vpm.Image(data, affine)
    assert img.shape == data.shape and np.array_equal(img.data, data)
    assert address(img.data) == address(img.data) and img.data.flags.f_contiguous
    assert np.allclose(img.affine, affine) and img.spacing == [2.0, 2.0, 2.0]
    with pytest.raises(ValueError, match="4 x 4"):
        vpm.Image(data, np.eye(3))
