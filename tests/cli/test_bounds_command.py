"""``p3d bounds`` on the command line: specs, meshes, placement options, JSON, refusals."""

from __future__ import annotations

import csv
import io
import json
import math
import os

import numpy as np
import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_ascii_stl


def record(*args):
    result = run("bounds", *args, "--json")
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.fixture
def block(tmp_path):
    """The block [0, 1] × [0, 2] × [0, 3] as ASCII STL (full float64 precision)."""
    path = tmp_path / "block.stl"
    write_ascii_stl(path, cube_triangles() * [1, 2, 3])
    return str(path)


def test_json_keys():
    r = record("box:1,2,3")
    assert {"source", "min", "max", "size", "center"} <= set(r)
    assert r["source"] == "box:1,2,3" and r["method"] == "vertices"
    assert r["min"] == [-1, -2, -3] and r["size"] == [2, 4, 6] and r["center"] == [0, 0, 0]


def test_table():
    result = run("bounds", "sphere:2", "--translate", "1,0,0")
    assert result.exit_code == 0
    assert "closed form" in result.stdout
    assert "min                     -1" in result.stdout


def test_rotate_is_exact_for_quarter_turns_and_composes_about_world_axes():
    # z:90 then x:90 takes the box's x axis to world z, y to world x, z to world y.
    r = record("box:1,2,3", "--rotate", "z:90", "--rotate", "x:90")
    assert r["max"] == [2, 3, 1]


def test_vector_axis_and_translate():
    r = record("cylinder:1,1,2", "--rotate", "1,1,0:45", "--translate", "0,0,5")
    a = np.array([0.5, -0.5, math.sqrt(0.5)])            # the cylinder's axis after the turn
    half = np.abs(a) * 2 + np.sqrt(1 - a * a)
    np.testing.assert_allclose(r["max"], half + [0, 0, 5], rtol=1e-15)
    np.testing.assert_allclose(r["min"], -half + [0, 0, 5], rtol=1e-15)


def test_quat_with_leading_minus_and_sign_symmetry():
    a = record("wedge:1,2,3", "--quat", "-0.7,0.1,0.7,0")
    b = record("wedge:1,2,3", "--quat", "0.7,-0.1,-0.7,0")
    c = record("wedge:1,2,3", "--quat=-7,1,7,0")               # normalised for the user
    np.testing.assert_allclose(a["min"], b["min"], rtol=1e-15)
    np.testing.assert_allclose(a["max"], c["max"], rtol=1e-14)


def test_scale_on_a_mesh_and_a_spec(block):
    r = record(block, "--scale", "2,1,0.5")
    assert r["min"] == [0, 0, 0] and r["max"] == [2, 2, 1.5]
    assert r["format"] == "stl-ascii" and r["faces"] == 12
    r = record("sphere:1", "--scale", "1,2,3")                # becomes the ellipsoid
    assert r["max"] == [1, 2, 3]


def test_mesh_matches_equivalent_spec(block):
    # The block is box:0.5,1,1.5 moved by (0.5, 1, 1.5): rotated about the origin, its box is
    # the spec's box moved by R (0.5, 1, 1.5).
    mesh = record(block, "--rotate", "1,2,3:40")
    spec = record("box:0.5,1,1.5", "--rotate", "1,2,3:40")
    from p3d_cli.geometry.rotation import rotation_from_axis_degrees
    shift = rotation_from_axis_degrees([1, 2, 3], 40) @ [0.5, 1, 1.5]
    np.testing.assert_allclose(mesh["max"], np.array(spec["max"]) + shift, rtol=1e-14)
    np.testing.assert_allclose(mesh["min"], np.array(spec["min"]) + shift, rtol=1e-14)


def test_tessellate():
    r = record("cylinder:1,1,1", "--tessellate", "6")
    assert r["format"] == "tessellated" and r["faces"] == 24
    assert r["max"][1] == pytest.approx(math.sqrt(3) / 2, rel=1e-15)   # a hexagon's inradius


def test_file_named_like_a_spec_is_reached_with_dot_slash(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_ascii_stl("box", cube_triangles() * 7)
    spec = run("bounds", "box", "--json")
    assert spec.exit_code == 0 and json.loads(spec.stdout)["max"] == [1, 1, 1]
    assert "./box" in spec.stderr                      # a warning says how to reach the file
    path = record("./box")
    assert path["max"] == [7, 7, 7]


def test_stdin(block):
    with open(block, "rb") as f:
        result = run("bounds", "-", "--format", "stl", "--json", input=f.read())
    assert result.exit_code == 0, result.output
    assert json.loads(result.stdout)["max"] == [1, 2, 3]


@pytest.mark.parametrize("args, words", [
    (["sphere:1,2,3"], ["sphere:1,2,3", "sx = sy = sz", "ellipsoid:1,2,3"]),
    (["cylinder:1,2,3"], ["sx = sy", "ecylinder:1,2,3"]),
    (["box:1,2"], ["box takes 3 numbers", "box:SX,SY,SZ"]),
    (["box:-1,1,1"], ["not positive"]),
    (["box:0,1,1"], ["not positive"]),
    (["cube:1,2,3"], ["no shape named 'cube'", "shapes are: box"]),
    (["box", "--quat", "0,0,0,0"], ["--quat", "zero quaternion"]),
    (["box", "--quat", "1,0,0"], ["--quat", "not 4"]),
    (["box", "--rotate", "z"], ["--rotate", "AXIS:DEGREES"]),
    (["box", "--rotate", "0,0,0:10"], ["--rotate", "no direction"]),
    (["box", "--rotate", "z:90", "--quat", "1,0,0,0"], ["--rotate/--quat", "both given"]),
    (["box", "--scale", "1,0,1"], ["--scale", "positive"]),
    (["box", "--scale", "1,2"], ["--scale"]),
    (["box", "--tessellate", "2"], ["--tessellate"]),
    (["missing.stl"], ["missing.stl"]),
])
def test_refusals_exit_2_with_one_error_line(args, words):
    result = run("bounds", *args)
    assert result.exit_code == 2, result.output
    assert "p3d: error:" in result.stderr
    for w in words:
        assert w in result.stderr
    assert "Traceback" not in result.output


def test_tessellate_refused_on_a_mesh(block):
    result = run("bounds", block, "--tessellate", "8")
    assert result.exit_code == 2
    assert "--tessellate" in result.stderr and "mesh" in result.stderr


def test_help_states_the_convention():
    text = run("bounds", "--help").stdout
    for phrase in ["right-hand rule", "each turn", "world", "W,X,Y,Z", "q and -q", "--translate",
                   "half-extents"]:
        assert phrase in " ".join(text.split()), phrase


def test_subprocess_entry_point():
    import subprocess
    import sys
    out = subprocess.run([sys.executable, "-m", "p3d_cli", "bounds", "corner", "--json"],
                         capture_output=True, text=True, cwd=os.path.dirname(__file__))
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["min"] == [-1, -1, -1]


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_batch_directory_files_from_and_csv(tmp_path, jobs):
    folder = tmp_path / "parts"
    folder.mkdir()
    for i in range(3):
        write_ascii_stl(folder / f"p{i}.stl", cube_triangles() * (i + 1))
    listing = tmp_path / "list.txt"
    listing.write_text(f"{tmp_path / 'missing.stl'}\n")
    result = run("bounds", str(folder), "box:1,2,3", "--files-from", str(listing), "--csv", "--jobs", jobs)
    assert result.exit_code == 2
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert [os.path.basename(r["source"]) for r in rows] == ["p0.stl", "p1.stl", "p2.stl", "box:1,2,3", "missing.stl"]
    assert [(r["max_x"], r["max_z"]) for r in rows[:3]] == [("1.0", "1.0"), ("2.0", "2.0"), ("3.0", "3.0")]
    assert (rows[3]["min_y"], rows[3]["max_z"], rows[3]["error"]) == ("-2.0", "3.0", "")
    assert rows[4]["error"].endswith("missing.stl: no such file; check the path (shape specs are box, "
                                     "wedge, corner, cylinder, sphere, ellipsoid, ecylinder, capsule)") and rows[4]["min_x"] == ""
    assert "p3d: 5 files: 4 ok, 1 error" in result.stderr


def test_batch_json_and_csv_together_is_a_usage_error():
    result = run("bounds", "box", "--json", "--csv")
    assert result.exit_code == 2 and "--json/--csv: both given" in result.stderr
