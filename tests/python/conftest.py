"""Fixtures of the Python package's tests (tests/python, run by ctest as python:pytest).

ctest puts the build tree's package on PYTHONPATH and names the build and source folders; run
by hand: PYTHONPATH=build/python /usr/bin/python3 -m pytest tests/python."""
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.environ.get("VPM_SOURCE_DIR", os.path.abspath(os.path.join(HERE, "..", "..")))
BUILD = os.environ.get("VPM_BUILD_DIR", os.path.join(SOURCE, "build"))
if not any(os.path.isfile(os.path.join(p, "vpm", "__init__.py")) for p in sys.path if p):
    sys.path.insert(0, os.path.join(BUILD, "python"))
os.environ.setdefault("POCL_CACHE_DIR", os.path.join(BUILD, "pocl-cache"))


def ellipsoid(shape=(40, 36, 30), radii=(30.0, 24.0, 18.0), voxel=2.0):
    """A smooth ellipsoid intensity image (values 0 outside, rising inside) and its affine: 2 mm
    voxels, the centre of the grid at world (10, -20, 5)."""
    affine = np.diag([voxel, voxel, voxel, 1.0])
    affine[:3, 3] = np.array([10.0, -20.0, 5.0]) - voxel * (np.array(shape) - 1) / 2
    i, j, k = np.meshgrid(*[np.arange(n) for n in shape], indexing="ij")
    x = [(idx - (n - 1) / 2) * voxel / r for idx, n, r in zip((i, j, k), shape, radii)]
    rho = np.sqrt(x[0] ** 2 + x[1] ** 2 + x[2] ** 2)
    data = np.where(rho < 1, 100 * (1.2 - rho) + 20 * np.sin(i / 3.0), 0).astype(np.float32)
    return data, affine


@pytest.fixture(scope="session")
def vpm():
    import vpm as module
    return module


@pytest.fixture(scope="session")
def cli():
    path = os.path.join(BUILD, "vpm")
    assert os.access(path, os.X_OK), f"{path}: build vpm first"
    return path


@pytest.fixture(scope="session")
def image_array():
    return ellipsoid()


@pytest.fixture(scope="session")
def small_mesh(vpm, image_array):
    data, affine = image_array
    mesh, report = vpm.mesh_image(data, affine=affine, target_vertices=500)
    assert isinstance(report, dict) and mesh.num_tets > 500
    return mesh


@pytest.fixture(scope="session")
def ball(vpm, small_mesh):
    return vpm.map_to_ball(small_mesh.copy(), source="ellipsoid")
