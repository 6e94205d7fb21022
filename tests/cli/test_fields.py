"""``--field`` on props, bounds and check: nested values as JSON, list indices, one line per input."""

from __future__ import annotations

import json

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl


@pytest.fixture
def cube(tmp_path):
    """A 1 x 2 x 3 box from (0.5, 0.5, 0.5): volume 6, centre (1, 1.5, 2)."""
    path = tmp_path / "cube.stl"
    write_binary_stl(path, cube_triangles() * [1, 2, 3] + 0.5)
    return str(path)


def test_props_nested_field_is_json(cube):
    result = run("props", cube, "--field", "bounds")
    assert result.exit_code == 0
    assert json.loads(result.stdout) == {"min": [0.5, 0.5, 0.5], "max": [1.5, 2.5, 3.5]}


def test_props_matrix_field_is_row_after_row_and_indices_pick_items(cube):
    inertia = json.loads(run("props", cube, "--json").stdout)["inertia"]
    assert run("props", cube, "--field", "inertia").stdout.split() == [repr(x) for row in inertia for x in row]
    result = run("props", cube, "--field", "center_of_mass.0", "--field", "center_of_mass.2",
                 "--field", "inertia.1.1", "--field", "bounds.max.1")
    assert result.exit_code == 0
    assert result.stdout.rstrip("\n").split("\t") == ["1.0", "2.0", repr(inertia[1][1]), "2.5"]


def test_index_out_of_range_is_a_usage_error(cube):
    result = run("props", cube, "--field", "center_of_mass.3")
    assert result.exit_code == 2 and "no field named 'center_of_mass.3'" in result.stderr
    assert "bounds.min" in result.stderr   # the list of fields names nested keys too


@pytest.mark.parametrize("command, name, expected", [
    ("props", "volume", "6.0"), ("bounds", "size.2", "3.0"), ("check", "ok", "true")])
def test_failing_input_keeps_lines_aligned(cube, tmp_path, command, name, expected):
    missing = tmp_path / "missing.stl"
    result = run(command, cube, missing, cube, "--field", name)
    assert result.exit_code == 2
    assert result.stdout.split("\n") == [expected, "", expected, ""]
    assert "missing.stl: no such file" in result.stderr


def test_bounds_fields(cube):
    result = run("bounds", cube, "--field", "min", "--field", "center.1", "--field", "warning_codes")
    assert result.exit_code == 0
    assert result.stdout == "0.5 0.5 0.5\t1.5\t\n"


def test_check_fields_nested(tmp_path):
    path = tmp_path / "open.stl"
    write_binary_stl(path, cube_triangles()[1:])
    result = run("check", path, "--field", "failed", "--field", "boundary_edges", "--field", "shell_list")
    assert result.exit_code == 1
    failed, edges, shells = result.stdout.rstrip("\n").split("\t")
    assert (failed, edges) == ("closed", "3")
    assert json.loads(shells) == [{"faces": 11, "first_face": 0, "volume": json.loads(
        run("check", path, "--json").stdout)["volume"]}]


@pytest.mark.parametrize("command", ["props", "bounds", "check"])
@pytest.mark.parametrize("other", ["--json", "--csv"])
def test_field_with_json_or_csv_is_a_usage_error(cube, command, other):
    result = run(command, cube, "--field", "source", other)
    assert result.exit_code == 2 and result.stdout == ""
    assert "both given" in result.stderr and "--field" in result.stderr


def test_a_result_json_cannot_hold_is_a_range_error_naming_the_field_not_a_bug():
    """Issue 27: --json of a result that overflowed float64 was an internal error (exit 3). The
    library now keeps such results finite (the centre of bounds at 1e308 is a number) or refuses
    them; the JSON writer stays the backstop: a record holding inf or nan is a range error that
    names the source and the field, never an internal error."""
    import pytest
    from click.testing import CliRunner

    from p3d_cli.cli.main import cli
    from p3d_cli.cli.output import dumps
    from p3d_cli.errors import RangeError

    result = CliRunner().invoke(cli, ["bounds", "box:1,1,1", "--translate", "1e308,0,0", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["center"] == [1e308, 0.0, 0.0]
    with pytest.raises(RangeError, match=r"^box:1,1,1: center\.0 is not a finite number \(float64 overflowed"):
        dumps({"source": "box:1,1,1", "min": [1.0, 0.0, 0.0], "center": [float("inf"), 0.0, 0.0]})
