"""A result's ``to_dict()`` is the record ``--json`` prints, built by the library, and its
``to_json()`` the very line; the common quantities are one attribute away."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from p3d_cli.cli.main import cli

from helpers.real_meshes import REPO
from helpers.record_schemas import validate

SAMPLES = sorted(str(p.relative_to(REPO)) for p in (REPO / "sample_meshes").iterdir()
                 if p.suffix in (".stl", ".obj", ".off"))
SPECS = ("box:1,2,3", "sphere:0.5", "cylinder:1,1,2", "capsule:1,2", "wedge:1,2,3")
ASSEMBLY = """units: mm
parts:
  - name: base
    mesh: {bracket}
    density: 2.7 g/cm^3
  - name: arm
    shape: box:10,20,30
    mass: 0.5 kg
    translate: [0, 0, 100]
"""


def printed(*args: str) -> str:
    run = CliRunner().invoke(cli, list(args), catch_exceptions=False)
    assert run.exit_code in (0, 1), run.output
    return run.stdout.rstrip("\n")


def plain(value) -> bool:
    """Only what ``json`` takes without help: no numpy scalar or array, no tuple."""
    if isinstance(value, dict):
        return all(isinstance(k, str) and plain(v) for k, v in value.items())
    if isinstance(value, list):
        return all(plain(v) for v in value)
    return value is None or type(value) in (str, int, float, bool)


def assert_same_record(result, kind: str, line: str) -> None:
    assert result.to_json() == line
    record = result.to_dict()
    assert plain(record) and json.loads(json.dumps(record)) == json.loads(line)
    assert list(record)[0] == "schema_version"
    validate(kind, result.to_json())


@pytest.mark.parametrize("thing", [*SAMPLES, *SPECS])
def test_props_bounds_and_check_records_are_the_command_lines(thing, monkeypatch):
    monkeypatch.chdir(REPO)
    assert_same_record(p3d.props(thing), "props", printed("props", thing, "--json"))
    assert_same_record(p3d.bounds(thing), "bounds", printed("bounds", thing, "--json"))
    if not thing.partition(":")[0] in p3d.SHAPES:
        assert_same_record(p3d.check(thing), "check", printed("check", thing, "--json"))


def test_placed_monte_carlo_and_about_records_are_the_command_lines(monkeypatch):
    monkeypatch.chdir(REPO)
    turn = p3d.Placement(scale=np.array([2.0, 2.0, 2.0]), rotation=p3d.rotation_from_axis_degrees("z", 30),
                         translation=np.array([1.0, 2.0, 3.0]))
    line = printed("props", "sample_meshes/bracket.stl", "--json", "--scale", "2", "--rotate", "z:30",
                   "--translate", "1,2,3", "--about", "1,0,0", "--density", "7.85")
    assert_same_record(p3d.props("sample_meshes/bracket.stl", turn, about=[1.0, 0.0, 0.0], density=7.85), "props",
                       line)
    line = printed("props", "box:1,2,3", "--json", "--method", "montecarlo", "--samples", "2000", "--seed", "3")
    assert_same_record(p3d.props("box:1,2,3", method="montecarlo", samples=2000, seed=3), "props", line)


def test_an_assemblys_record_holds_its_parts(tmp_path):
    path = tmp_path / "arm.yaml"
    path.write_text(ASSEMBLY.format(bracket=REPO / "sample_meshes" / "bracket.stl"))
    result = p3d.props(str(path))
    assert_same_record(result, "props", printed("props", str(path), "--json"))
    parts = result.to_dict()["parts"]
    assert [part["name"] for part in parts] == ["base", "arm"] and "schema_version" not in parts[0]
    assert_same_record(p3d.bounds(str(path)), "bounds", printed("bounds", str(path), "--json"))
    assert_same_record(p3d.check(str(path)), "check", printed("check", str(path), "--json"))


@pytest.mark.parametrize("scene", sorted(p.name for p in (REPO / "examples").glob("*.yaml")))
def test_solve_records_are_the_command_lines(scene):
    path = str(REPO / "examples" / scene)
    result = p3d.solve_scene(p3d.load_scene(path))
    assert_same_record(result, "solve", printed("solve", path, "--json"))
    assert "settings" not in result.to_dict()      # p3d solve reads no project settings
    stepped = p3d.solve_scene(p3d.load_scene(path), steps=50, dt=0.001)
    assert_same_record(stepped, "solve", printed("solve", path, "--json", "--steps", "50", "--dt", "0.001"))


def test_a_record_that_overflowed_is_refused_as_the_command_line_refuses_it():
    box = p3d.props("box:1,2,3")
    result = dataclasses.replace(box, properties=dataclasses.replace(box.properties, mass=float("inf")))
    assert result.to_dict()["mass"] == float("inf")       # the values as they are
    with pytest.raises(p3d.P3DError, match="is not a finite number") as info:
        result.to_json()
    assert isinstance(info.value, ValueError)


def test_the_common_quantities_are_one_step_away():
    result = p3d.props("box:1,2,3", density=2.0)
    p, f = result.properties, result.facts
    assert (result.volume, result.mass, result.density) == (p.volume, p.mass, p.density) == (48.0, 96.0, 2.0)
    for name in ("center_of_mass", "inertia", "principal_moments", "principal_axes"):
        assert getattr(result, name) is getattr(p, name)
    assert result.bounds is f.bounds
    box = p3d.bounds("box:1,2,3", p3d.Placement(translation=np.array([1.0, 0.0, 0.0])))
    assert box.min.tolist() == [0.0, -2.0, -3.0] and box.max.tolist() == [2.0, 2.0, 3.0]
    assert box.size.tolist() == [2.0, 4.0, 6.0] and box.center.tolist() == [1.0, 0.0, 0.0]
    assert box.diagonal == box.bounds.diagonal == pytest.approx(np.sqrt(56.0))
    verdict = p3d.check(str(REPO / "sample_meshes" / "bracket.stl"))
    r = verdict.report
    assert (verdict.volume, verdict.faces, verdict.closed, verdict.manifold) == (
        r.solid_volume, r.faces, r.closed, r.manifold)
    solved = p3d.solve_scene(p3d.load_scene(str(REPO / "examples" / "pendulum.yaml")))
    assert solved.body(solved.bodies[-1].name) is solved.bodies[-1]
    with pytest.raises(KeyError):
        solved.body("no such body")
