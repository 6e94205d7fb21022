"""``p3d robot check``: planted faults are caught with the right link and rule; a good or filled
description passes; exit statuses 0, 1, 2."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from p3d_cli.cli.main import cli
from p3d_cli.robots import check_robot, load_robot


def _failures(path, packages=None, **options):
    checks = check_robot(load_robot(path, packages), **options)
    return {c.link: sorted({p.rule for p in c.problems}) for c in checks if not c.ok}


def run(*args):
    return CliRunner().invoke(cli, list(map(str, args)))


def test_plausible_description_passes(arm):
    assert _failures(arm.urdf(), arm.packages) == {}


@pytest.mark.parametrize("fault, link, rule", [
    ({"base_mass": "-5.4"}, "base", "mass > 0"),
    ({"base_ixx": "0.05"}, "base", "triangle inequality"),        # 0.0132 + 0.0173 < 0.05
    ({"base_ixx": "-0.0132"}, "base", "positive definite"),
    ({"upper_com": "0.005 0 0.9"}, "upper", "com inside"),        # the link ends at 0.43 m
    ({"upper_mass": "1900"}, "upper", "density"),                  # grams in a metre model
])
@pytest.mark.parametrize("kind", ["urdf", "sdf"])
def test_planted_faults_are_caught_on_the_right_link(arm, monkeypatch, fault, link, rule, kind):
    monkeypatch.setenv("GZ_SIM_RESOURCE_PATH", str(arm.root))
    path = getattr(arm, kind)(**fault)
    failures = _failures(path, arm.packages)
    assert list(failures) == [link]
    assert rule in failures[link]


def test_non_positive_definite_tensor_with_off_diagonal_terms(arm, tmp_path):
    # Eigenvalues of [[1, 2], [2, 1]] are 3 and -1: every diagonal entry positive, still not PD.
    text = arm.urdf().read_text().replace('ixx="0.0132" ixy="0"', 'ixx="0.0132" ixy="0.03"')
    path = tmp_path / "offdiag.urdf"
    path.write_text(text)
    assert _failures(path, arm.packages) == {"base": ["positive definite"]}


def test_moments_far_from_the_geometry_are_caught(arm):
    path = arm.urdf(base_ixx="0.0132")
    assert _failures(path, arm.packages, tolerance=1.01) == {"upper": ["principal moments"]}
    # Loose by default: real links are not uniform.
    assert _failures(path, arm.packages) == {}


def test_mjcf_declared_inertials_are_checked(arm):
    path = arm.mjcf(upper_inertial='<inertial pos="0 0 2" mass="2" diaginertia="0.01 0.01 0.05"/>')
    failures = _failures(path)
    assert failures == {"upper": ["com inside", "principal moments", "triangle inequality"]}


def test_cli_lines_name_link_value_and_rule_and_exit_1(arm):
    result = run("robot", "check", arm.urdf(base_mass="-5.4"), "--package-path",
                 f"arm_description={arm.package}")
    assert result.exit_code == 1
    assert "arm.urdf: link 'base': mass -5.4 is not positive (rule: mass > 0)" in result.stdout


def test_cli_json_one_record_per_link(arm):
    result = run("robot", "check", arm.urdf(), "--package-path", f"arm_description={arm.package}", "--json")
    assert result.exit_code == 0
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["link"] for r in records] == ["base", "upper", "tool"]
    assert all(r["ok"] for r in records)
    assert records[0]["implied_density"] == pytest.approx(5.4 / (3.141592653589793 * 0.08 ** 2 * 0.1))
    assert records[2]["notes"] == ["declares no inertial"]


def test_cli_unreadable_description_exits_2(arm, tmp_path):
    result = run("robot", "check", arm.urdf())   # no package path for the wedge
    assert result.exit_code == 2
    assert ("link 'upper': collision[1]: mesh package://arm_description/meshes/wedge.obj: no such file; "
            "give --package-path arm_description=DIR") in result.stderr
    result = run("robot", "check", tmp_path / "missing.urdf")
    assert result.exit_code == 2 and "cannot be read" in result.stderr


def test_ros_package_path_is_searched(arm, monkeypatch):
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(arm.root))
    assert run("robot", "check", arm.urdf()).exit_code == 0


def test_open_geometry_is_not_compared(arm, tmp_path):
    """An open mesh still bounds the centre of mass, but its volume and moments mean nothing."""
    data = (arm.root / "upper.stl").read_bytes()
    count = int.from_bytes(data[80:84], "little")
    (arm.root / "upper.stl").write_bytes(data[:80] + (count - 1).to_bytes(4, "little") + data[84:-50])
    checks = check_robot(load_robot(arm.urdf(upper_mass="1900"), arm.packages))
    upper = checks[1]
    assert upper.ok and any("not a closed solid" in note for note in upper.notes)


def test_mesh_in_millimetres_without_its_scale_is_caught(arm, tmp_path):
    text = arm.urdf().read_text().replace('<mesh filename="upper.stl" scale="0.001 0.001 0.001"/>',
                                          '<mesh filename="upper.stl"/>')
    path = tmp_path / "mm.urdf"
    path.write_text(text)
    failures = _failures(path, arm.packages)
    assert list(failures) == ["upper"] and "density" in failures["upper"]


def test_visual_geometry_on_request(arm):
    # The visual sphere of radius 0.5 m is 0.52 m^3: 1.9 kg over it is 3.6 kg/m^3, not plausible.
    assert _failures(arm.urdf(), arm.packages, role="visual") == {"upper": ["density", "principal moments"]}
    result = run("robot", "check", arm.urdf(), "--package-path", f"arm_description={arm.package}",
                 "--from", "visual", "--json")
    assert result.exit_code == 1
    assert [r["ok"] for r in map(json.loads, result.stdout.splitlines())] == [True, False, True]


def test_mjcf_inertia_from_geoms_is_said(arm, tmp_path):
    text = arm.mjcf().read_text().replace('<compiler ', '<compiler inertiafromgeom="true" ')
    path = tmp_path / "fromgeom.xml"
    path.write_text(text)
    result = run("robot", "check", path)
    assert result.exit_code == 0 and "MuJoCo ignores every declared <inertial>" in result.stderr
