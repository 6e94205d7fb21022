"""Units: the same part in mm with g/cm³ and in m with kg/m³ gives the same SI numbers; every
unit string the help shows parses; the millimetre/kg-per-cubic-metre slip is caught."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

import p3d_cli as p3d
from helpers.cli import run
from helpers.meshes import write_ascii_stl
from p3d_cli.errors import UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.geometry.rotation import rotation_from_rpy
from p3d_cli.units import EXAMPLES, LENGTHS, quantity_si, resolve

WEDGE = p3d.parse_shape("wedge:20,35,50").triangles() + [40.0, -10.0, 5.0]      # millimetres


@pytest.fixture
def parts(tmp_path):
    """The same wedge as a file in millimetres and as a file in metres (float64 ASCII STL)."""
    mm, m = tmp_path / "part_mm.stl", tmp_path / "part_m.stl"
    write_ascii_stl(mm, WEDGE)
    write_ascii_stl(m, WEDGE / 1000.0)
    return str(mm), str(m)


def test_mm_with_g_per_cm3_equals_m_with_kg_per_m3(parts):
    mm, m = parts
    a = p3d.props(mm, units="mm", density="7.85 g/cm^3", about=[10, 20, 30]).properties
    b = p3d.props(m, units="m", density="7850 kg/m^3", about=[0.01, 0.02, 0.03]).properties
    assert a.mass == pytest.approx(b.mass, rel=1e-15, abs=0)
    for key in ("center_of_mass", "inertia", "inertia_origin", "inertia_about"):
        x, y = getattr(a, key), getattr(b, key)
        np.testing.assert_allclose(x, y, rtol=1e-15, atol=1e-15 * np.abs(y).max())
    # And against the hand conversion: volume in mm³ → m³, density 7850 kg/m³.
    plain = p3d.props(mm).properties
    assert a.mass == pytest.approx(plain.volume * 1e-9 * 7850, rel=1e-15)
    np.testing.assert_allclose(a.inertia, plain.inertia * 7850 * 1e-15, rtol=1e-14, atol=1e-30)


def test_placement_and_output_units(parts):
    mm, _ = parts
    rotation = rotation_from_rpy(0.1, 0.2, 0.3)
    si = p3d.props(mm, Placement(rotation=rotation, translation=[100, 0, 0]), units="mm", density="7.85g/cm^3")
    grams = p3d.props(mm, Placement(rotation=rotation, translation=[100, 0, 0]), units="mm",
                      density="7.85g/cm^3", output_units="mm,g")
    assert si.units["length"] == "m" and grams.units == {
        "system": "converted", "length": "mm", "volume": "mm^3", "density": "g/mm^3", "mass": "g",
        "inertia": "g*mm^2", "mesh_length": "mm"}
    assert grams.properties.mass == pytest.approx(si.properties.mass * 1e3, rel=1e-14)
    np.testing.assert_allclose(grams.properties.center_of_mass, si.properties.center_of_mass * 1e3, rtol=1e-14)
    np.testing.assert_allclose(grams.properties.inertia, si.properties.inertia * 1e9, rtol=1e-13,
                               atol=1e-13 * np.abs(grams.properties.inertia).max())
    np.testing.assert_allclose(si.facts.bounds.min * 1e3, grams.facts.bounds.min, rtol=1e-14)
    # The record keeps the placement the user gave (millimetres), not the converted one.
    assert si.details["placement"]["translation"].tolist() == [100, 0, 0]


@pytest.mark.parametrize("unit", sorted(LENGTHS))
def test_length_units(unit):
    r = p3d.props("box:1,1,1", units=unit, density="1000 kg/m^3")
    assert r.properties.volume == pytest.approx(8 * LENGTHS[unit] ** 3, rel=1e-15)
    assert r.properties.mass == pytest.approx(8000 * LENGTHS[unit] ** 3, rel=1e-15)


def test_every_unit_string_in_the_help_parses():
    help_text = run("props", "--help").output + run("bounds", "--help").output
    shown = set(re.findall(r"\d[\d.]*(?:g/cm\^3|kg/m\^3|lb/in\^3|kg|lb|g)\b", help_text))
    assert set(EXAMPLES) <= shown | set(EXAMPLES)
    assert len(shown) >= 5, shown
    for text in shown | set(EXAMPLES):
        kind = "density" if "/" in text else "mass"
        assert quantity_si(text, kind, kind) > 0
    assert quantity_si("2.5lb", "mass", "mass") == pytest.approx(2.5 * 0.45359237, rel=1e-15)
    assert quantity_si("0.284lb/in^3", "density", "density") == pytest.approx(
        0.284 * 0.45359237 / 0.0254 ** 3, rel=1e-14)
    for length in LENGTHS:
        assert run("props", "box", "--units", length, "--json").exit_code == 0


@pytest.mark.parametrize("kwargs, where, words", [
    (dict(density="7.85 g/cm^3"), "units", "length unit is not given"),
    (dict(units="mm", density=7850.0), "density", "has no unit"),
    (dict(units="mm", mass=2.0), "mass", "has no unit"),
    (dict(units="mm", density="2.5 kg"), "density", "not a density"),
    (dict(units="mm", mass="7 g/cm^3"), "mass", "not a mass"),
    (dict(units="mm", density="lots"), "density", "not a quantity"),
    (dict(units="mm", density="-3 g/cm^3"), "density", "not positive"),
    (dict(units="yd"), "units", "unknown length unit"),
    (dict(units="mm", output_units="km,g"), "output_units", "not a length and a mass"),
    (dict(output_units="mm,g"), "output_units", "without units"),
])
def test_refusals_name_the_parameter(kwargs, where, words):
    with pytest.raises(UsageError) as info:
        p3d.props("box", **kwargs)
    assert info.value.where == where and words in info.value.what


def test_cli_errors_name_flags():
    result = run("props", "box", "--units", "mm", "--density", "7850")
    assert result.exit_code == 2
    assert result.stderr.startswith("p3d: error: --density:") and "--units mm" in result.stderr


def test_the_slip_warning_fires_on_the_slip_only(parts):
    mm, m = parts
    slip = p3d.props(mm, density=7850)
    assert any("1e9 times too large" in w for w in slip.warnings)
    assert slip.units["system"] == "mesh"
    for sane in (p3d.props(mm, units="mm", density="7850kg/m^3"),   # units given
                 p3d.props(m, density=7850),                        # a part 0.05 across: metres
                 p3d.props(mm, density=7.85e-3),                    # g/mm³ by hand
                 p3d.props(mm),                                     # no density
                 p3d.props(mm, mass=2.0)):                          # a mass, not a density
        assert not sane.warnings, sane.warnings


def test_json_and_table_say_the_units(parts):
    mm, _ = parts
    record = json.loads(run("props", mm, "--units", "mm", "--density", "7.85g/cm^3", "--json").stdout)
    assert record["units"]["mass"] == "kg" and record["units"]["inertia"] == "kg*m^2"
    bare = json.loads(run("props", mm, "--json").stdout)
    assert bare["units"]["system"] == "mesh"
    table = run("props", mm, "--units", "mm", "--density", "7.85g/cm^3").stdout
    assert "units             length m, mass kg, inertia kg*m^2 (mesh in mm)" in table
    assert "the mesh's own" in run("props", mm).stdout
    bounds = json.loads(run("bounds", mm, "--units", "mm", "--json").stdout)
    np.testing.assert_allclose(bounds["max"], WEDGE.reshape(-1, 3).max(axis=0) / 1000, rtol=1e-15)


def test_resolve_without_units_changes_nothing():
    assert resolve(None, None, 2.0, None) == (None, 2.0, None)
