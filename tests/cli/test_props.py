"""``p3d props`` on the command line: output forms, several inputs, warnings, exit statuses."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli.cli.main import cli

REPO_SAMPLE = __import__("pathlib").Path(__file__).resolve().parents[2] / "sample_meshes" / "bracket.stl"

REQUIRED_KEYS = {"source", "faces", "closed", "volume", "mass", "density", "center_of_mass", "inertia",
                 "inertia_origin", "principal_moments", "principal_axes", "bounds", "warnings"}


@pytest.fixture
def cube(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, cube_triangles() * [1, 2, 3] + 0.5)
    return str(path)


def test_table_by_default(cube):
    result = run("props", cube)
    assert result.exit_code == 0, result.output
    assert "volume            6" in result.stdout
    assert "closed: yes" in result.stdout and "method: exact" in result.stdout


def test_json_keys_and_full_precision(cube):
    result = run("props", cube, "--json", "--density", "3")
    assert result.exit_code == 0
    record = json.loads(result.stdout)
    assert REQUIRED_KEYS <= set(record)
    assert record["volume"] == 6.0 and record["mass"] == 18.0 and record["density"] == 3.0
    assert record["closed"] is True and record["faces"] == 12 and record["warnings"] == []
    assert record["center_of_mass"] == [1.0, 1.5, 2.0]
    assert record["bounds"] == {"min": [0.5, 0.5, 0.5], "max": [1.5, 2.5, 3.5]}
    expected = 18.0 / 12 * np.diag([4 + 9, 1 + 9, 1 + 4])
    np.testing.assert_allclose(record["inertia"], expected, rtol=1e-14)
    # principal moments ascending, axes a right-handed frame
    assert record["principal_moments"] == sorted(record["principal_moments"])
    assert np.linalg.det(np.array(record["principal_axes"])) == pytest.approx(1.0)


def test_mass_derives_density(cube):
    record = json.loads(run("props", cube, "--json", "--mass", "12").stdout)
    assert record["density"] == 2.0 and record["mass"] == 12.0


def test_mass_and_density_together_is_usage_error(cube):
    result = run("props", cube, "--mass", "1", "--density", "2")
    assert result.exit_code == 2
    assert result.stderr.startswith("p3d: error: --mass/--density: both given")


def test_about_point_accepts_negative_values(cube):
    record = json.loads(run("props", cube, "--json", "--about", "-1,0,2.5").stdout)
    assert record["about"] == [-1.0, 0.0, 2.5]
    d = np.array(record["center_of_mass"]) - np.array([-1.0, 0.0, 2.5])
    shifted = np.array(record["inertia"]) + 6 * (d @ d * np.eye(3) - np.outer(d, d))
    np.testing.assert_allclose(record["inertia_about"], shifted, rtol=1e-13)


def test_fields_are_bare_and_tab_separated(cube):
    result = run("props", cube, "--field", "volume", "--field", "bounds.min")
    assert result.exit_code == 0
    assert result.stdout == "6.0\t0.5 0.5 0.5\n"


def test_unknown_field_is_usage_error(cube):
    result = run("props", cube, "--field", "volumen")
    assert result.exit_code == 2
    assert "no field named 'volumen'" in result.stderr and "fields are:" in result.stderr


def test_several_inputs_one_bad(cube, tmp_path):
    missing = str(tmp_path / "missing.stl")
    result = run("props", cube, missing, cube, "--json")
    assert result.exit_code == 2
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert [line["source"] for line in lines] == [cube, missing, cube]
    assert lines[1]["error"].startswith(missing + ": no such file")
    assert lines[0]["volume"] == lines[2]["volume"] == 6.0
    assert f"p3d: error: {missing}: no such file" in result.stderr


def test_inward_wound_mesh_warns_and_keeps_sign(tmp_path):
    # Issue 12.6: an inward-wound mesh is measured as the solid its faces enclose (positive
    # volume, mass and inertia); the sign is kept in signed_volume and the warning.
    path = tmp_path / "inside_out.stl"
    write_binary_stl(path, cube_triangles()[:, ::-1])
    result = run("props", str(path), "--json")
    assert result.exit_code == 0
    record = json.loads(result.stdout)
    assert record["volume"] == 1.0 and record["mass"] == 1.0 and record["signed_volume"] == -1.0
    assert np.all(np.diag(record["inertia"]) > 0)
    assert any("negative" in w and "wound inward" in w for w in record["warnings"])
    assert "p3d: warning:" in result.stderr
    strict = run("props", str(path), "--strict")
    assert strict.exit_code == 1


def test_open_mesh_warns(tmp_path):
    path = tmp_path / "open.stl"
    write_binary_stl(path, cube_triangles()[:-2])
    record = json.loads(run("props", str(path), "--json").stdout)
    assert record["closed"] is False
    assert any("not closed" in w for w in record["warnings"])


def test_flat_mesh_gives_zero_volume_and_null_center(tmp_path):
    path = tmp_path / "flat.stl"
    square = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    write_binary_stl(path, np.concatenate([square, square[:, ::-1]]))
    result = run("props", str(path), "--json")
    assert result.exit_code == 0
    record = json.loads(result.stdout)
    assert record["volume"] == 0.0 and record["center_of_mass"] is None and record["inertia"] is None
    assert any("no volume" in w for w in record["warnings"])
    assert "volume            0" in run("props", str(path)).stdout


def test_table_never_hides_small_values(tmp_path):
    path = tmp_path / "tiny.stl"
    write_binary_stl(path, cube_triangles() * 2.0 ** -14)   # exact in float32
    out = run("props", str(path)).stdout
    assert f"volume            {2.0 ** -42:.10g}" in out and "0.000000" not in out


@pytest.mark.parametrize("content, message", [
    (b"", "file is empty"),
    (b"\x00" * 200, "binary STL holds no triangles"),
])
def test_bad_files_get_one_line(tmp_path, content, message):
    path = tmp_path / "bad.stl"
    path.write_bytes(content)
    result = run("props", str(path))
    assert result.exit_code == 2
    assert result.stderr.count("\n") == 1 and message in result.stderr
    assert "Traceback" not in result.output


def test_directory_without_meshes(tmp_path):
    (tmp_path / "notes.txt").write_text("hello")
    result = run("props", str(tmp_path))
    assert result.exit_code == 2
    assert "directory holds no mesh files" in result.stderr


def test_no_input_is_usage_error():
    result = run("props")
    assert result.exit_code == 2 and "no input given" in result.stderr


def test_stdin_and_module_entry_point(cube):
    with open(cube, "rb") as f:
        done = subprocess.run([sys.executable, "-m", "p3d_cli", "props", "-", "--field", "volume"],
                              stdin=f, capture_output=True, text=True, check=False)
    assert done.returncode == 0 and done.stdout == "6.0\n"


def test_every_command_has_help_with_example():
    for name in cli.commands:
        result = run(name, "--help")
        assert result.exit_code == 0, name
        assert "Example" in result.stdout, f"p3d {name} --help shows no example"


def test_json_records_how_the_result_was_made(cube):
    placed = json.loads(run("props", "box:1,2,3", "--rotate", "z:90", "--translate", "0,0,-1", "--json").stdout)
    assert placed["placement"]["translation"] == [0.0, 0.0, -1.0]
    np.testing.assert_allclose(placed["placement"]["rotation"], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)
    assert "scale" not in placed["placement"]
    sampled = json.loads(run("props", cube, "--method", "montecarlo", "--samples", "5000", "--seed", "7",
                             "--json").stdout)
    assert (sampled["method"], sampled["samples"], sampled["seed"]) == ("montecarlo", 5000, 7)
    tessellated = json.loads(run("props", "sphere:1", "--tessellate", "16", "--json").stdout)
    assert tessellated["tessellate"] == 16
    plain = json.loads(run("props", cube, "--json").stdout)
    assert not {"placement", "samples", "seed", "tessellate"} & set(plain)


def test_a_closed_pipe_ends_quietly(tmp_path):
    """p3d ... | head: when the reader goes away, p3d stops like any Unix filter (SIGPIPE),
    with nothing on stderr."""
    import shutil
    import signal

    for i in range(40):
        shutil.copy(REPO_SAMPLE, tmp_path / f"part{i:02}.stl")
    proc = subprocess.Popen([sys.executable, "-m", "p3d_cli", "props", str(tmp_path), "--json", "--jobs", "1"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    first = proc.stdout.readline()
    proc.stdout.close()
    _, err = proc.communicate(timeout=60)
    assert json.loads(first)["volume"] == 4500.0
    assert proc.returncode in (0, -signal.SIGPIPE)
    assert b"Traceback" not in err and b"error" not in err


def test_point_faces_are_not_closed():
    from p3d_cli.mesh.closed import closed_exact

    points = np.repeat(np.eye(3)[:, None, :], 3, axis=1)   # three faces, each a single point
    assert closed_exact(points) is False
