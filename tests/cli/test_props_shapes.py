"""``p3d props`` on shape specs and with placement options: exact closed forms, placed solids."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_ascii_stl
from p3d_cli.geometry.rotation import rotation_from_axis_degrees


def record(*args):
    result = run("props", *args, "--json")
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.fixture
def block(tmp_path):
    """The block [-1, 1] × [-2, 2] × [-3, 3] as ASCII STL: the mesh twin of box:1,2,3."""
    path = tmp_path / "block.stl"
    write_ascii_stl(path, (cube_triangles() * 2 - 1) * [1, 2, 3])
    return str(path)


def test_spec_in_the_same_output_as_a_mesh(block):
    spec, mesh = record("box:1,2,3"), record(block)
    assert spec["format"] == "primitive" and spec["method"] == "exact"
    assert set(spec) == set(mesh)
    for key in ("volume", "center_of_mass", "inertia"):
        np.testing.assert_allclose(spec[key], mesh[key], rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("spec, volume, inertia_diag", [
    ("box:1,2,3", 48, [48 * (16 + 36) / 12, 48 * (4 + 36) / 12, 48 * (4 + 16) / 12]),
    ("sphere:2", 32 * math.pi / 3, [0.4 * 32 * math.pi / 3 * 4] * 3),
    ("cylinder:1,1,2", 4 * math.pi, [4 * math.pi * (3 + 16) / 12] * 2 + [2 * math.pi]),
    # Corner: C_ii = 1/5, so I_ii = tr(C) - C_ii = 2/5 (docs/method.md, "Wedge and corner vertices"; derived by hand).
    ("corner", 4 / 3, [0.4] * 3),
])
def test_closed_forms(spec, volume, inertia_diag):
    r = record(spec)
    assert r["volume"] == pytest.approx(volume, rel=1e-15)
    np.testing.assert_allclose(np.diag(r["inertia"]), inertia_diag, rtol=1e-14)


def test_density_and_mass():
    r = record("wedge:1,2,3", "--density", "2")
    assert r["volume"] == 24 and r["mass"] == 48
    r = record("wedge:1,2,3", "--mass", "6")
    assert r["mass"] == 6 and r["density"] == 0.25
    np.testing.assert_allclose(r["center_of_mass"], [-1 / 3, -2 / 3, 0], rtol=1e-15)


def test_placed_solid_has_rotated_inertia_and_moved_centre():
    plain = record("wedge:1,2,3")
    placed = record("wedge:1,2,3", "--rotate", "z:30", "--rotate", "1,1,1:50", "--translate", "1,2,3")
    r = rotation_from_axis_degrees([1, 1, 1], 50) @ rotation_from_axis_degrees("z", 30)
    np.testing.assert_allclose(placed["inertia"], r @ np.array(plain["inertia"]) @ r.T, atol=1e-13)
    np.testing.assert_allclose(placed["center_of_mass"], r @ plain["center_of_mass"] + [1, 2, 3], rtol=1e-14)
    np.testing.assert_allclose(placed["principal_moments"], plain["principal_moments"], rtol=1e-13)
    assert placed["volume"] == plain["volume"]


def test_scale_by_eq9_on_mesh_equals_spec(block):
    mesh = record(block, "--scale", "2,0.5,3")
    spec = record("box:2,1,9")
    for key in ("volume", "center_of_mass", "inertia"):
        np.testing.assert_allclose(mesh[key], spec[key], rtol=1e-14, atol=1e-12)
    assert mesh["bounds"]["max"] == [2, 1, 9]


def test_uneven_scale_turns_sphere_into_ellipsoid():
    a = record("sphere", "--scale", "1,2,3")
    b = record("ellipsoid:1,2,3")
    np.testing.assert_allclose(a["inertia"], b["inertia"], rtol=1e-15)


def test_placed_mesh_bounds_are_the_placed_solids(block):
    r = record(block, "--rotate", "x:90", "--translate", "0,0,10")
    assert r["bounds"]["min"] == [-1, -3, 8] and r["bounds"]["max"] == [1, 3, 12]


def test_tessellate_shows_the_polyhedral_error():
    exact = record("cylinder")["volume"]
    coarse = record("cylinder", "--tessellate", "8")
    fine = record("cylinder", "--tessellate", "64")
    assert coarse["format"] == "tessellated" and coarse["closed"] is True
    assert coarse["volume"] == pytest.approx(8 * math.sin(2 * math.pi / 8), rel=1e-14)
    e8, e64 = exact - coarse["volume"], exact - fine["volume"]
    assert 0 < e64 < e8 and e8 / e64 == pytest.approx(64, rel=0.05)     # O(1/N²)


@pytest.mark.parametrize("args, words", [
    (["sphere:1,2,3"], ["sphere:1,2,3", "sx = sy = sz", "ellipsoid"]),
    (["cylinder:2,1,1"], ["cylinder:2,1,1", "sx = sy", "ecylinder"]),
    (["sphere:1,2"], ["takes 1 or 3 numbers"]),
    (["box:1,2,3,4"], ["takes 3 numbers"]),
    (["box:0,1,1"], ["not positive"]),
    (["box", "--scale", "0,1,1"], ["--scale"]),          # -1,1,1 mirrors now (issue 13)
    (["box", "--quat", "0,0,0,0"], ["--quat"]),
])
def test_refusals(args, words):
    result = run("props", *args)
    assert result.exit_code == 2, result.output
    assert result.stderr.startswith("p3d: error:")
    for w in words:
        assert w in result.stderr


def test_one_bad_spec_does_not_stop_the_others():
    result = run("props", "box", "sphere:1,2,3", "corner", "--json")
    assert result.exit_code == 2
    lines = [json.loads(x) for x in result.stdout.splitlines()]
    assert [("error" in x) for x in lines] == [False, True, False]
