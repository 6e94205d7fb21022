"""One convention for every command: ``check`` reports the volume ``props`` reports, in the same
units and with the same sign, for every kind of file (issue 26, item 4)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from helpers.meshes import CUBE_FACES, CUBE_VERTICES, write_binary_stl
from p3d_cli.cli.main import cli

CUBE = CUBE_VERTICES[CUBE_FACES] * [1.0, 2.0, 3.0]


def records(*args):
    run = CliRunner().invoke(cli, [str(a) for a in args])
    return run, [json.loads(line) for line in run.output.splitlines() if line.startswith("{")]


def test_an_inward_mesh_has_one_volume_and_one_sign(tmp_path):
    path = tmp_path / "inward.stl"
    write_binary_stl(path, CUBE[:, ::-1])
    props = p3d.props(path)
    check = p3d.check(path)
    assert props.properties.volume == pytest.approx(6.0) and check.report.solid_volume == pytest.approx(6.0)
    assert any("inward" in w for w in props.warnings) and "outward" in check.failed
    _, (props_record,) = records("props", path, "--json")
    run, (check_record,) = records("check", path, "--json")
    assert props_record["volume"] == check_record["volume"] == pytest.approx(6.0)
    assert props_record["signed_volume"] == check_record["signed_volume"] == pytest.approx(-6.0)
    assert props_record["units"]["volume"] == check_record["units"]["volume"] == "mesh unit^3"
    text = CliRunner().invoke(cli, ["check", str(path)]).output
    assert "volume 6)" in text and "signed volume -6 is negative: faces point inward" in text


AMF = ('<?xml version="1.0"?><amf unit="{unit}"><object id="1"><mesh><vertices>{v}</vertices><volume>{t}</volume>'
       "</mesh></object></amf>")


@pytest.mark.parametrize("unit, factor", [("millimeter", 1e-3), ("inch", 0.0254), ("micron", 1e-6)])
def test_a_scene_file_is_in_metres_for_every_command(tmp_path, unit, factor):
    vertices = "".join(f"<vertex><coordinates><x>{x}</x><y>{y}</y><z>{z}</z></coordinates></vertex>"
                       for x, y, z in (CUBE_VERTICES * [1.0, 2.0, 3.0]).tolist())
    triangles = "".join(f"<triangle><v1>{a}</v1><v2>{b}</v2><v3>{c}</v3></triangle>" for a, b, c in CUBE_FACES)
    path = tmp_path / "cube.amf"
    path.write_text(AMF.format(unit=unit, v=vertices, t=triangles))
    props = p3d.props(path)
    check = p3d.check(path)
    assert props.properties.volume == pytest.approx(6.0 * factor ** 3, rel=1e-12)
    assert check.report.solid_volume == pytest.approx(props.properties.volume, rel=1e-12)
    _, (props_record,) = records("props", path, "--json")
    _, (check_record,) = records("check", path, "--json")
    assert check_record["volume"] == pytest.approx(props_record["volume"], rel=1e-12)
    assert check_record["units"]["volume"] == props_record["units"]["volume"] == "m^3"
    bounds = p3d.bounds(path)
    np.testing.assert_allclose(bounds.bounds.max, np.array([1.0, 2.0, 3.0]) * factor, rtol=1e-12)
    # --min-volume is compared in the same unit as the volume reported
    assert p3d.check(path, min_volume=5.9 * factor ** 3).ok
    assert "min-volume" in p3d.check(path, min_volume=6.1 * factor ** 3).failed


def test_problem_locations_of_a_scene_file_are_in_metres(tmp_path):
    vertices = "".join(f"<vertex><coordinates><x>{x}</x><y>{y}</y><z>{z}</z></coordinates></vertex>"
                       for x, y, z in (CUBE_VERTICES * 1000).tolist())
    triangles = "".join(f"<triangle><v1>{a}</v1><v2>{b}</v2><v3>{c}</v3></triangle>" for a, b, c in CUBE_FACES[1:])
    path = tmp_path / "open.amf"
    path.write_text(AMF.format(unit="millimeter", v=vertices, t=triangles))
    check = p3d.check(path)
    points = np.array([p for sample in check.report.boundary_edge_samples for p in sample.points])
    assert points.size and np.abs(points).max() == pytest.approx(1.0)


ROBOTS = Path(__file__).resolve().parents[1].parent / "shared" / "real-robots"


@pytest.mark.parametrize("relative", [
    "px4_models/models/omniquad_base/meshes/iris_prop_cw.dae",
    "px4_models/models/rover_differential/meshes/rover_differential_base.dae",
    "prius/prius_description/meshes/hybrid_body.obj",
    "prius/prius_description/meshes/steering_wheel.obj",
])
def test_real_open_meshes_get_one_volume_from_every_command(relative):
    path = ROBOTS / relative
    if not path.is_file():
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true but {path} is missing")
        pytest.skip(f"{path} not found")
    props = p3d.props(path)
    check = p3d.check(path)
    assert check.report.solid_volume == pytest.approx(props.properties.volume, rel=1e-9)
    assert props.facts.closed is check.report.closed
    if not check.report.closed:
        assert any("not closed" in w for w in props.warnings) and "closed" in check.failed


def test_ply_extra_properties_and_unknown_elements_are_read(tmp_path):
    """Readers never refuse a file for a field p3d does not use."""
    text = ("ply\nformat ascii 1.0\ncomment x\nobj_info y\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nproperty uchar red\nproperty list uchar float uv\nelement face 4\n"
            "property list uchar int vertex_indices\nproperty float quality\nelement edge 1\nproperty int vertex1\n"
            "property int vertex2\nelement material 1\nproperty list uchar uchar name\nend_header\n"
            "0 0 0 1 2 0.5 0.5\n1 0 0 1 0\n0 1 0 1 1 3\n0 0 1 1 0\n3 0 2 1 0.1\n3 0 1 3 0.1\n3 0 3 2 0.1\n"
            "3 1 2 3 0.1\n0 1\n3 65 66 67\n")
    path = tmp_path / "extra.ply"
    path.write_text(text)
    result = p3d.props(path)
    assert result.properties.volume == pytest.approx(1 / 6) and result.facts.closed
