"""Assemblies: placed, mirrored, nested parts of mixed materials against independent sums."""

from __future__ import annotations

import json
from fractions import Fraction
import math

import numpy as np
import pytest

import p3d_cli as p3d
from helpers.cli import run
from helpers.meshes import write_ascii_stl
from p3d_cli.errors import InputError
from p3d_cli.geometry.inertia import implausibilities
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.results import Bounds, MassProperties
from p3d_cli.geometry.rotation import rotation_from_axis_degrees, rotation_from_rpy

MM = 1e-3
#: The base plate's triangles (mm): a box 100 x 80 x 10 centred below the origin.
BASE = p3d.parse_shape("box:50,40,5").triangles() + [0.0, 0.0, -5.0]


@pytest.fixture
def files(tmp_path):
    write_ascii_stl(tmp_path / "base.stl", BASE)
    (tmp_path / "bracket.yaml").write_text(
        "parts:\n"
        "  - name: clip\n"
        "    shape: wedge:5,5,10\n"
        "    density: 2.7 g/cm^3\n"
        "    scale: [1, -1, 1]\n"
        "    translate: [0, 0, 10]\n")
    (tmp_path / "assembly.yaml").write_text(
        "units: mm\n"
        "parts:\n"
        "  - name: base\n"
        "    mesh: base.stl\n"
        "    density: 7.85 g/cm^3\n"
        "  - name: arm\n"
        "    shape: box:10,20,30\n"
        "    mass: 0.5 kg\n"
        "    translate: [0, 0, 100]\n"
        "    rotate: {axis: z, degrees: 30}\n"
        "    scale: [1, -1, 1]\n"
        "  - name: bracket\n"
        "    assembly: bracket.yaml\n"
        "    translate: [40, 0, 5]\n"
        "    rpy: [0, 0, 1.5707963267948966]\n"
        "  - name: pin\n"
        "    shape: capsule:3,8\n"
        "    density: 8000 kg/m^3\n"
        "    quat: [0.9238795325112867, 0.3826834323650898, 0, 0]\n"
        "    translate: [-30, 20, 40]\n")
    return tmp_path


def placed(moments, scale, rotation, translation):
    """The test's own placement: V' = |det S| V, c' = R S c + t, C' = |det S| R S C S Rᵀ."""
    s = np.diag(scale)
    a = rotation @ s
    det = abs(np.prod(scale))
    return det * moments.volume, a @ moments.center + translation, det * a @ moments.central @ a.T


def parallel_axis_sum(parts):
    """(mass, centre, inertia about the centre) of (density, volume, centre, central) parts."""
    masses = np.array([rho * v for rho, v, _, _ in parts])
    total = masses.sum()
    center = sum(m * c for m, (_, _, c, _) in zip(masses, parts)) / total
    inertia = np.zeros((3, 3))
    for m, (rho, _, c, central) in zip(masses, parts):
        d = c - center
        inertia += rho * (np.trace(central) * np.eye(3) - central) + m * (d @ d * np.eye(3) - np.outer(d, d))
    return total, center, inertia


def oracle_parts():
    """Each part's unplaced exact integrals (metres) and its whole placement, by hand."""
    base = triangle_moments(BASE * MM)
    arm = p3d.parse_shape("box:10,20,30").moments()
    arm_density = 0.5 / (8 * 10 * 20 * 30 * MM ** 3)
    clip = p3d.parse_shape("wedge:5,5,10").moments()
    pin = p3d.parse_shape("capsule:3,8").moments()
    quarter = rotation_from_rpy(0, 0, math.pi / 2)
    tilt = rotation_from_axis_degrees("x", 45)
    return [
        (7850.0, placed(base, np.ones(3), np.eye(3), np.zeros(3))),
        (arm_density, placed(arm, np.array([1, -1, 1]) * MM, rotation_from_axis_degrees("z", 30),
                             np.array([0, 0, 100]) * MM)),
        # Nested: clip placed in the bracket (mirror, lift), the bracket in the assembly.
        (2700.0, placed(clip, np.array([1, -1, 1]) * MM, quarter, quarter @ np.array([0, 0, 10]) * MM
                        + np.array([40, 0, 5]) * MM)),
        (8000.0, placed(pin, np.ones(3) * MM, tilt, np.array([-30, 20, 40]) * MM)),
    ]


def test_assembly_equals_the_parallel_axis_sum_of_exact_parts(files):
    result = p3d.props(files / "assembly.yaml", about=[10, 0, 0])
    parts = [(rho, *m) for rho, m in oracle_parts()]
    mass, center, inertia = parallel_axis_sum(parts)
    p = result.properties
    assert p.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(p.center_of_mass, center, rtol=0, atol=1e-12 * 0.1)
    np.testing.assert_allclose(p.inertia, inertia, rtol=0, atol=1e-12 * np.abs(inertia).max())
    d = center - np.array([0.01, 0, 0])
    about = inertia + mass * (d @ d * np.eye(3) - np.outer(d, d))
    np.testing.assert_allclose(p.inertia_about, about, rtol=0, atol=1e-12 * np.abs(about).max())
    assert [r.details["name"] for r in result.parts] == ["base", "arm", "bracket/clip", "pin"]
    assert result.units["mass"] == "kg" and not result.warnings
    for part, (rho, (volume, c, _)) in zip(result.parts, oracle_parts()):
        assert part.properties.volume == pytest.approx(volume, rel=1e-13) and volume > 0
        assert part.properties.mass == pytest.approx(rho * volume, rel=1e-12)
        np.testing.assert_allclose(part.properties.center_of_mass, c, atol=1e-15)
    # Principal frame as quaternion reproduces the inertia.
    frame = p3d.quaternion_matrix(p.principal_quaternion) if hasattr(p3d, "quaternion_matrix") else None
    if frame is None:
        from p3d_cli.geometry.rotation import quaternion_matrix
        frame = quaternion_matrix(p.principal_quaternion)
    np.testing.assert_allclose(frame @ np.diag(p.principal_moments) @ frame.T, p.inertia,
                               atol=1e-12 * np.abs(p.inertia).max())


def test_uniform_density_assembly_equals_the_concatenated_placed_triangles(files):
    """Polyhedral parts that do not overlap, one density: the union's triangles, integrated."""
    (files / "same.yaml").write_text(
        "parts:\n"
        "  - {mesh: base.stl}\n"
        "  - {shape: 'box:10,20,30', translate: [0, 0, 100], rotate: {axis: z, degrees: 30}, scale: [1, -1, 1]}\n"
        "  - {assembly: bracket_plain.yaml, translate: [40, 0, 5], rpy: [0, 0, 1.5707963267948966]}\n")
    (files / "bracket_plain.yaml").write_text(
        "parts:\n  - {shape: 'corner:5,5,10', scale: [-1, 1, 1], translate: [0, 0, 10]}\n")
    arm = p3d.parse_shape("box:10,20,30").triangles() * [1, -1, 1]
    arm = arm[:, [0, 2, 1]] @ rotation_from_axis_degrees("z", 30).T + [0, 0, 100]
    quarter = rotation_from_rpy(0, 0, math.pi / 2)
    clip = (p3d.parse_shape("corner:5,5,10").triangles() * [-1, 1, 1])[:, [0, 2, 1]] + [0, 0, 10]
    clip = clip @ quarter.T + [40, 0, 5]
    union = triangle_moments(np.concatenate([BASE, arm, clip]))
    result = p3d.props(files / "same.yaml", density=3.0).properties
    assert result.volume == pytest.approx(union.volume, rel=1e-12)
    np.testing.assert_allclose(result.center_of_mass, union.center, atol=1e-12 * 100)
    np.testing.assert_allclose(result.second_moments, 3.0 * union.central, atol=1e-12 * np.abs(3 * union.central).max())


def test_combine_equals_the_assembly_file(files):
    write_ascii_stl(files / "arm.stl", p3d.parse_shape("box:10,20,30").triangles() + [0, 0, 100])
    (files / "pair.yaml").write_text(
        "units: mm\n"
        "parts:\n"
        "  - {mesh: base.stl, density: 2.7g/cm^3, rotate: {axis: x, degrees: 20}, translate: [1, 2, 3]}\n"
        "  - {mesh: arm.stl, density: 2.7g/cm^3, rotate: {axis: x, degrees: 20}, translate: [1, 2, 3]}\n")
    common = ["--units", "mm", "--density", "2.7g/cm^3", "--json", "--about", "5,5,5"]
    by_file = json.loads(run("props", str(files / "pair.yaml"), "--json", "--about", "5,5,5").stdout)
    combined = run("props", str(files / "base.stl"), str(files / "arm.stl"), "--combine", *common,
                   "--rotate", "x:20", "--translate", "1,2,3")
    assert combined.exit_code == 0, combined.output
    combined = json.loads(combined.stdout)
    for key in ("volume", "mass", "center_of_mass", "inertia", "inertia_about", "principal_moments"):
        np.testing.assert_allclose(combined[key], by_file[key], rtol=1e-12, atol=1e-18)
    assert len(combined["parts"]) == 2 and combined["format"] == "assembly"
    # --mass is the whole's.
    whole = json.loads(run("props", str(files / "base.stl"), str(files / "arm.stl"), "--combine",
                           "--units", "mm", "--mass", "2kg", "--json").stdout)
    assert whole["mass"] == pytest.approx(2.0, rel=1e-14)
    assert sum(p["mass"] for p in whole["parts"]) == pytest.approx(2.0, rel=1e-14)


def test_csv_has_a_row_per_part_and_a_total(files):
    result = run("props", str(files / "assembly.yaml"), "--csv")
    lines = result.stdout.strip().splitlines()
    assert result.exit_code == 0 and len(lines) == 1 + 4 + 1
    assert lines[2].startswith(f"{files / 'assembly.yaml'}#arm,") and ",assembly," in lines[-1]
    table = run("props", str(files / "assembly.yaml")).stdout
    assert "part bracket/clip:" in table and "whole " in table


def test_bounds_of_an_assembly(files):
    result = p3d.bounds(files / "assembly.yaml")
    each = [p3d.bounds(r.facts.source, None) for r in p3d.props(files / "assembly.yaml").parts]
    assert each and result.format == "assembly"
    box = p3d.props(files / "assembly.yaml").facts.bounds
    np.testing.assert_array_equal(result.bounds.min, box.min)
    np.testing.assert_allclose(result.bounds.max[2], 0.130, rtol=1e-15)       # the arm's top, in metres


@pytest.mark.parametrize("part, where, words", [
    ("{shape: 'box:1,1,1', mass: lots}", "parts[0].mass", "not a quantity"),
    ("{shape: 'box:1,1,1', mass: 2}", "parts[0].mass", "has no unit"),
    ("{shape: 'box:1,1,1', colour: red}", "parts[0].colour", "unknown key"),
    ("{shape: 'box:1,1'}", "parts[0].shape", "box takes 3 numbers"),
    ("{mesh: missing.stl}", "parts[0].mesh", "no such file"),
    ("{shape: 'box', rotate: {axis: w, degrees: 3}}", "parts[0].rotate", "neither x, y, z"),
    ("{shape: 'box', translate: [1, 2]}", "parts[0].translate", "expected 3"),
    ("{shape: 'box', scale: 0}", "parts[0].scale", "not one or three"),
    ("{shape: 'box', rpy: [0, 0, 1], quat: [1, 0, 0, 0]}", "parts[0].quat/rpy", "both given"),
    ("{shape: 'box', mesh: base.stl}", "parts[0]", "exactly one of"),
    ("{assembly: loop.yaml}", "loop.yaml", "includes itself"),
])
def test_errors_name_the_part_and_the_key(files, part, where, words):
    (files / "loop.yaml").write_text("parts:\n  - {assembly: loop.yaml}\n")
    path = files / "bad.yaml"
    path.write_text(f"units: mm\nparts:\n  - {part}\n")
    with pytest.raises(InputError) as info:
        p3d.props(path)
    assert info.value.where.endswith(where) and words in info.value.what, info.value.message
    result = run("props", str(path))
    assert result.exit_code == 2 and "Traceback" not in result.output and where in result.stderr


def test_nested_assembly_needs_a_uniform_scale(files):
    (files / "shear.yaml").write_text("parts:\n  - {assembly: bracket.yaml, scale: [1, 2, 1]}\n")
    with pytest.raises(InputError, match="not uniform"):
        p3d.props(files / "shear.yaml", units="mm")


def test_plausibility_checks():
    def props(volume, mass, principal, center):
        return MassProperties(volume, mass / volume, mass, np.array(center, float), np.diag(principal),
                              np.diag(principal), np.array(principal, float), np.eye(3), np.diag(principal))
    box = Bounds(np.zeros(3), np.ones(3))
    assert implausibilities(props(1.0, 1.0, [1, 1, 1.5], [0.5, 0.5, 0.5]), box) == []
    assert any("triangle" in w for w in implausibilities(props(1.0, 1.0, [1, 1, 2.5], [0.5] * 3), box))
    assert any("not both positive" in w for w in implausibilities(props(-1.0, -1.0, [1, 1, 1], [0.5] * 3), box))
    assert any("outside the bounds" in w for w in implausibilities(props(1.0, 1.0, [1, 1, 1], [2, 0.5, 0.5]), box))
    # Every real shape passes.
    for spec in ("box:1,2,3", "wedge:1,2,3", "corner:3,2,1", "capsule:1,4", "ecylinder:1,3,2"):
        assert not p3d.props(spec, p3d.Placement(scale=[1, -1, 1], translation=[5, 0, 0])).warnings


def test_a_nested_assembly_part_gives_its_parts_a_density_or_their_total_mass(tmp_path):
    # Two unit boxes (volume 8 each) in a nested file that gives no material.
    (tmp_path / "pair.yaml").write_text("parts:\n  - {shape: box}\n  - {shape: box, translate: [2, 0, 0]}\n")
    (tmp_path / "dense.yaml").write_text("parts:\n  - {assembly: pair.yaml, density: 3}\n  - {shape: box, "
                                         "translate: [4, 0, 0], density: 1}\n")
    got = p3d.props(tmp_path / "dense.yaml")
    assert [r.properties.mass for r in got.parts] == pytest.approx([24, 24, 8], rel=1e-15)
    assert got.properties.mass == pytest.approx(56, rel=1e-15)
    # A mass on the nested part is its parts' total, shared by volume (equal here).
    (tmp_path / "heavy.yaml").write_text("parts:\n  - {assembly: pair.yaml, mass: 10}\n  - {shape: box, "
                                         "translate: [4, 0, 0], mass: 1}\n")
    got = p3d.props(tmp_path / "heavy.yaml")
    assert [r.properties.mass for r in got.parts] == pytest.approx([5, 5, 1], rel=1e-15)
    np.testing.assert_allclose(got.properties.center_of_mass, [(5 * 0 + 5 * 2 + 4) / 11, 0, 0], rtol=1e-15)
    # The nested part's inertia is that of its parts scaled by the same factor: a 4 x 2 x 2 block
    # of mass 10 about its own centre, 10/3 (b² + c²) about x.
    nested = p3d.props(tmp_path / "pair.yaml", mass=10)
    assert nested.properties.inertia[0, 0] == pytest.approx(10 / 3 * (1 + 1), rel=1e-14)


def test_a_mass_given_twice_over_nested_parts_is_refused(tmp_path):
    (tmp_path / "pair.yaml").write_text("parts:\n  - {shape: box, mass: 2}\n  - {shape: box, translate: [2, 0, 0]}\n")
    (tmp_path / "top.yaml").write_text("parts:\n  - {assembly: pair.yaml, mass: 10}\n")
    with pytest.raises(InputError) as info:
        p3d.props(tmp_path / "top.yaml")
    assert info.value.where.endswith("pair.yaml: parts[0]") and "mass" in info.value.what
    (tmp_path / "top.yaml").write_text("parts:\n  - {assembly: pair.yaml, density: 10}\n")
    assert p3d.props(tmp_path / "top.yaml").parts[1].properties.mass == pytest.approx(80)
    (tmp_path / "plain.yaml").write_text("parts:\n  - {assembly: pair.yaml, density: 10}\n")
    with pytest.raises(InputError, match="whole's mass"):
        p3d.props(tmp_path / "plain.yaml", mass=5)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8])
def test_the_whole_has_a_bound_that_covers_its_error(tmp_path, offset):
    """Mesh parts far from the origin: the whole's error against exact rational arithmetic on
    the union's triangles (the parts do not overlap) is within its stated bound."""
    from helpers.exact import exact_moments

    rng = np.random.default_rng(7)
    torus = p3d.parse_shape("ellipsoid:1,2,0.5").tessellate(24)
    pieces = [torus * [1.0, 1.0, 1.0] + [offset, 0, 0], torus[:, :, [1, 2, 0]] * 0.7 + [offset + 5.1, 3.3, 0.2]]
    pieces = [p + rng.uniform(-1e-3, 1e-3, 3) for p in pieces]
    for i, tri in enumerate(pieces):
        write_ascii_stl(tmp_path / f"p{i}.stl", tri)
    (tmp_path / "a.yaml").write_text("parts:\n  - {mesh: p0.stl}\n  - {mesh: p1.stl}\n")
    result = p3d.props(tmp_path / "a.yaml")
    bound = result.uncertainty
    assert bound is not None
    reread = np.concatenate([p3d.load_mesh(tmp_path / f"p{i}.stl").triangles() for i in range(2)])
    exact = exact_moments(reread)
    got = result.properties
    assert abs(got.volume - float(exact.volume)) <= bound["volume"]
    center_error = np.array([abs(Fraction(x) - c) for x, c in zip(got.center_of_mass, exact.center)], float)
    assert (center_error <= bound["center_of_mass"]).all()
    trace = sum(exact.central[i][i] for i in range(3))
    for i in range(3):
        for j in range(3):
            truth = (trace if i == j else 0) - exact.central[i][j]
            assert abs(Fraction(got.inertia[i, j]) - truth) <= Fraction(bound["inertia"][i, j])
    # Honest but not empty: a few orders of magnitude above float64's rounding of the result.
    assert (bound["inertia"] < 1e-6 * np.abs(got.inertia).max()).all()
