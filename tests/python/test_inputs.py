"""Inputs as neuroimaging pipelines write them: FreeSurfer .mgz/.mgh volumes (written here by
nibabel) read by vpm itself, nibabel images passed in, FreeSurfer colour tables."""
import subprocess

import nibabel as nib
import numpy as np
import pytest


def mgh_image(data, affine):
    img = nib.MGHImage(data, affine)
    return img


@pytest.mark.parametrize("dtype,suffix", [(np.uint8, ".mgz"), (np.int16, ".mgh"), (np.int32, ".mgz"),
                                          (np.float32, ".mgz")])
def test_mgh_matches_nibabel(vpm, tmp_path, image_array, dtype, suffix):
    data, _ = image_array
    # an oblique, anisotropic voxel -> RAS affine (FreeSurfer's LIA orientation, rotated)
    c, s = np.cos(0.3), np.sin(0.3)
    rot = np.array([[-1, 0, 0], [0, 0, 1], [0, -1, 0]]) @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    affine = np.eye(4)
    affine[:3, :3] = rot * [1.0, 1.5, 0.8]
    affine[:3, 3] = [12.5, -30.25, 7.0]
    path = str(tmp_path / ("brain" + suffix))
    nib.save(mgh_image(data.astype(dtype), affine), path)
    theirs = nib.load(path)
    ours = vpm.read_image(path)
    assert ours.affine_source == "mgh"
    assert ours.shape == theirs.shape
    assert np.allclose(ours.affine, theirs.affine, atol=1e-4)
    assert np.array_equal(ours.data, np.asanyarray(theirs.dataobj).astype(np.float32))


def test_mgz_meshes_like_the_nifti_it_came_from(vpm, cli, tmp_path, image_array):
    data, affine = image_array
    nib.save(nib.Nifti1Image(data, affine), str(tmp_path / "b.nii.gz"))
    nib.save(nib.MGHImage(data, affine), str(tmp_path / "b.mgz"))
    a, _ = vpm.mesh_image(str(tmp_path / "b.nii.gz"), target_vertices=300)
    b, _ = vpm.mesh_image(str(tmp_path / "b.mgz"), target_vertices=300)
    assert a.num_tets == b.num_tets and np.allclose(a.vertices, b.vertices, atol=1e-4)
    c, _ = vpm.mesh_image(nib.load(str(tmp_path / "b.mgz")), target_vertices=300)  # a nibabel image
    assert np.allclose(c.vertices, b.vertices, atol=1e-4)
    # the command line reads it too
    r = subprocess.run([cli, "mesh-image", str(tmp_path / "b.mgz"), "--target-vertices", "300", "-o",
                        str(tmp_path / "cli.vtu")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert vpm.read_mesh(str(tmp_path / "cli.vtu")).num_tets == b.num_tets


def test_truncated_mgz_is_refused(vpm, tmp_path, image_array):
    import gzip
    data, affine = image_array
    p = tmp_path / "t.mgz"
    nib.save(nib.MGHImage(data, affine), str(p))
    raw = gzip.open(p).read()
    gzip.open(p, "wb").write(raw[:284 + 1000])
    with pytest.raises(ValueError, match="truncated"):
        vpm.read_image(str(p))


def test_label_tables(vpm, tmp_path):
    lut = tmp_path / "FreeSurferColorLUT.txt"
    lut.write_text("#No. Label Name:  R G B A\n0 Unknown 0 0 0 0\n11 Left-Caudate 122 186 220 0\n"
                   "50 Right-Caudate 122 186 220 0\n")
    assert vpm.read_label_names(str(lut)) == {0: "Unknown", 11: "Left-Caudate", 50: "Right-Caudate"}
    names = vpm.read_label_names("/usr/share/mricron/templates/aal.nii.txt")
    assert names[71] == "Caudate_L" and len(names) == 116
    lut.write_text("11 Left-Caudate 122 186 220\n")
    with pytest.raises(ValueError, match="FreeSurferColorLUT.txt:1"):
        vpm.read_label_names(str(lut))
