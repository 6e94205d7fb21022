"""``p3d props --emit urdf|mjcf|sdf``: the printed <inertial> block, put in a description, reads
back (yourdfpy, MuJoCo, p3d's SDF reader) as the numbers of ``p3d props --json``."""

from __future__ import annotations

import json

import numpy as np
import pytest

from p3d_cli.robots import load_robot
from helpers.cli import run
from helpers.robot_arm import box_mesh, write_stl

ARGS = ("--units", "mm", "--density", "2700kg/m^3", "--rpy", "0.1,0.2,0.3", "--translate", "5,0,-3")


@pytest.fixture
def part(tmp_path):
    path = tmp_path / "part.stl"
    write_stl(path, *box_mesh((40.0, 60.0, 200.0), (-10.0, -30.0, 5.0)))
    record = json.loads(run("props", path, *ARGS, "--json").stdout)
    return path, record


def _emit(path, kind, *extra):
    result = run("props", path, *ARGS, "--emit", kind, *extra)
    assert result.exit_code == 0, result.output
    assert result.stdout.startswith("<!-- p3d: inertial of ") and "SI (kg, m, kg*m^2)" in result.stdout
    return result.stdout


def _same(mass, center, inertia, record):
    assert mass == pytest.approx(record["mass"], rel=1e-15)
    np.testing.assert_allclose(center, record["center_of_mass"], rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(inertia, record["inertia"], rtol=1e-12, atol=1e-18)


def test_urdf_block_reads_back_in_yourdfpy(part, tmp_path):
    yourdfpy = pytest.importorskip("yourdfpy")
    path, record = part
    block = _emit(path, "urdf")
    urdf = tmp_path / "one.urdf"
    urdf.write_text(f'<robot name="one"><link name="body">{block}</link></robot>')
    inertial = yourdfpy.URDF.load(str(urdf), build_scene_graph=False, load_meshes=False).link_map["body"].inertial
    _same(inertial.mass, inertial.origin[:3, 3], inertial.inertia, record)


def test_mjcf_block_compiles_in_mujoco(part, tmp_path):
    mujoco = pytest.importorskip("mujoco")
    from p3d_cli.geometry.rotation import quaternion_matrix

    path, record = part
    block = _emit(path, "mjcf")
    xml = tmp_path / "one.xml"
    xml.write_text(f'<mujoco><worldbody><body name="body"><freejoint/>{block}</body></worldbody></mujoco>')
    model = mujoco.MjModel.from_xml_path(str(xml))
    r = quaternion_matrix(model.body_iquat[1])
    _same(model.body_mass[1], model.body_ipos[1], r @ np.diag(model.body_inertia[1]) @ r.T,
          {**record, "inertia": record["inertia"]})


def test_sdf_block_reads_back(part, tmp_path):
    path, record = part
    block = _emit(path, "sdf")
    sdf = tmp_path / "one.sdf"
    sdf.write_text(f'<sdf version="1.9"><model name="m"><link name="body">{block}</link></model></sdf>')
    inertial = load_robot(sdf).links[0].inertial
    _same(inertial.mass, inertial.center, inertial.inertia, record)


def test_assembly_emits_the_whole(part, tmp_path):
    path, _ = part
    both = run("props", path, path, "--combine", "--units", "mm", "--density", "2700kg/m^3", "--emit", "urdf")
    assert both.exit_code == 0, both.output
    one = run("props", path, "--units", "mm", "--density", "2700kg/m^3", "--json")
    mass = 2 * json.loads(one.stdout)["mass"]
    assert f'<mass value="{mass!r}"/>' in both.stdout


def test_without_units_the_comment_says_so(part):
    path, _ = part
    result = run("props", path, "--emit", "mjcf")
    assert "SI only if the mesh is in metres" in result.stdout
