"""Library errors reach Python with the command line's messages: InputError as ValueError,
NumericalError as vpm.NumericalError; a progress callback that raises stops the work."""
import subprocess

import numpy as np
import pytest


def cli_error(cli, *args):
    r = subprocess.run([cli, *args], capture_output=True, text=True)
    assert r.returncode == 2, r
    return r.stderr.strip().split(": error: ", 1)[1]


def test_input_errors_are_value_errors_with_the_cli_message(vpm, cli, tmp_path):
    bad = tmp_path / "bad.mesh"
    bad.write_text("MeshVersionFormatted 1\nDimension 3\nVertices\n2\n0 0 0 0\n")
    message = cli_error(cli, "stats", str(bad))
    with pytest.raises(ValueError) as e:
        vpm.read_mesh(str(bad))
    assert str(e.value) == message and "bad.mesh" in message
    missing = str(tmp_path / "missing.nii.gz")
    with pytest.raises(ValueError) as e:
        vpm.read_image(missing)
    assert "missing.nii.gz" in str(e.value)


def test_numerical_error(vpm, small_mesh):
    assert issubclass(vpm.NumericalError, RuntimeError)
    # a registration whose flow must fold tets (ten landmarks sent to each other's places), with
    # the repairs off, is refused: NumericalError with the library's message, nothing returned
    out, _ = vpm.map_to_ball(small_mesh.copy(), device="host")
    v = out.vertices
    inner = np.flatnonzero(np.linalg.norm(v, axis=1) < 0.7)
    rng = np.random.default_rng(0)
    ids = rng.choice(inner, 10, replace=False)
    with pytest.raises(vpm.NumericalError, match="registration folded the mesh: [0-9]+ of [0-9]+ tets inverted"):
        vpm.register(out, landmarks=v[ids], targets=v[ids[rng.permutation(10)]], untangle=False, restore=False,
                     rigid=False, rk_steps=1, device="host")


def test_bad_options_name_themselves(vpm, small_mesh):
    with pytest.raises(ValueError, match="sphere density 'nope'"):
        vpm.map_to_ball(small_mesh.copy(), sphere="nope")
    with pytest.raises(ValueError, match="tolerance"):
        vpm.map_to_ball(small_mesh.copy(), tolerance=-1)
    with pytest.raises(ValueError, match="landmarks"):
        vpm.register(small_mesh)
    with pytest.raises(TypeError):
        vpm.map_to_ball(small_mesh.copy(), no_such_option=1)


def test_progress_callback(vpm, small_mesh):
    lines = []
    vpm.map_to_ball(small_mesh.copy(), progress=lines.append, device="host")
    assert lines and all(isinstance(x, str) for x in lines)

    class Stop(Exception):
        pass

    def stop(line):
        raise Stop(line)
    with pytest.raises(Stop):
        vpm.map_to_ball(small_mesh.copy(), progress=stop, device="host")
