"""``p3d robot check``: planted faults are caught with the right link and rule; a good or filled
description passes; exit statuses 0, 1, 2."""

from __future__ import annotations

import json

import numpy as np

import pytest

from helpers.cli import run
from p3d_cli.robots import check_robot, load_robot


def _failures(path, packages=None, **options):
    checks = check_robot(load_robot(path, packages), **options)
    return {c.link: sorted({p.rule for p in c.problems}) for c in checks if not c.ok}


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
    assert _failures(path, arm.packages, tolerance=1.01) == {"upper": ["moments"]}
    # Loose by default: real links are not uniform.
    assert _failures(path, arm.packages) == {}


def test_mjcf_declared_inertials_are_checked(arm):
    path = arm.mjcf(upper_inertial='<inertial pos="0 0 2" mass="2" diaginertia="0.01 0.01 0.05"/>')
    failures = _failures(path)
    assert failures == {"upper": ["com inside", "moments", "triangle inequality"]}


def test_cli_lines_name_link_value_and_rule_and_exit_1(arm):
    result = run("robot", "check", arm.urdf(base_mass="-5.4"), "--package-path",
                 f"arm_description={arm.package}")
    assert result.exit_code == 1
    assert "arm.urdf: link 'base': mass -5.4 is not positive (rule: mass > 0; from collision geometry, tolerance x2)" in result.stdout


def test_cli_json_one_record_per_link(arm):
    result = run("robot", "check", arm.urdf(), "--package-path", f"arm_description={arm.package}", "--json")
    assert result.exit_code == 0
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["link"] for r in records] == ["base", "upper", "tool"]
    assert all(r["ok"] for r in records)
    assert records[0]["implied_density"] == pytest.approx(5.4 / (3.141592653589793 * 0.08 ** 2 * 0.1))
    assert records[2]["notes"] == ["declares no inertial"]


def test_cli_unreadable_description_exits_2(arm, tmp_path):
    # No package path for the wedge, and no package arm_description near the description.
    arm.package.rename(tmp_path / "moved")
    result = run("robot", "check", arm.urdf())
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
    checks = check_robot(load_robot(arm.urdf(upper_mass="1900"), arm.packages), role="collision")
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
    assert _failures(arm.urdf(), arm.packages, role="visual") == {"upper": ["density", "moments"]}
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


# Issue #25 item 3: check compares like with like.

ROTOR = """<robot name="rotor">
  <link name="rotor">
    <collision><geometry><cylinder radius="0.02" length="0.2"/></geometry></collision>
    <inertial><origin xyz="0 0 0"/><mass value="0.2"/>
      <inertia ixx="{xx}" ixy="0" ixz="0" iyy="{yy}" iyz="0" izz="{zz}"/></inertial>
  </link>
</robot>"""


def test_a_rotor_with_the_right_moments_about_the_wrong_axis_fails(tmp_path):
    """Unitree B2's rotors: the axial moment declared about x. The sorted principal moments
    agree, so the old rule passed it."""
    axial, radial = 0.2 * 0.02 ** 2 / 2, 0.2 * (3 * 0.02 ** 2 + 0.2 ** 2) / 12
    right, wrong = tmp_path / "right.urdf", tmp_path / "wrong.urdf"
    right.write_text(ROTOR.format(xx=radial, yy=radial, zz=axial))
    wrong.write_text(ROTOR.format(xx=axial, yy=radial, zz=radial))
    assert _failures(right) == {}
    (check,) = check_robot(load_robot(wrong))
    assert [p.rule for p in check.problems] == ["moments"]
    assert check.problems[0].message.startswith("about the geometry's principal axes (z, ")  # the axial first
    np.testing.assert_allclose(sorted(check.moment_ratios), sorted([axial / radial, 1.0, radial / axial]), rtol=1e-9)


def test_massless_frames_are_reported_not_failed(tmp_path):
    """gym fetch's camera frames (mass 0, no geometry) and the shadow hand's tips (1 g, zero
    inertia): frames, not failures; a negative number still fails."""
    path = tmp_path / "frames.xml"
    path.write_text('<mujoco><worldbody><body name="camera"><inertial pos="0 0 0" mass="0" diaginertia="0 0 0">'
                    '</inertial></body><body name="tip"><inertial pos="0 0 0" mass="0.001" diaginertia="0 0 0"/>'
                    '<geom size="0.01"/></body><body name="bad"><inertial pos="0 0 0" mass="0.0005" '
                    'diaginertia="-1 1 1"/></body></worldbody></mujoco>')
    checks = {c.link: c for c in check_robot(load_robot(path))}
    assert checks["camera"].status == checks["tip"].status == "frame"
    assert checks["bad"].status == "failed" and checks["bad"].problems[0].rule == "positive definite"
    result = run("robot", "check", path)
    assert result.exit_code == 1 and "3 links, 1 failed, 2 massless frames: bad" in result.stderr


def test_require_inertial_fails_links_with_geometry_and_no_inertial(arm):
    assert _failures(arm.urdf(), arm.packages) == {}  # tool has no geometry either
    path = arm.urdf()
    text = path.read_text()
    start, end = text.index("<inertial>"), text.index("</inertial>") + len("</inertial>")
    path.write_text(text[:start] + text[end:])  # base: geometry, no inertial
    assert _failures(path, arm.packages) == {}
    assert _failures(path, arm.packages, require_inertial=True) == {"base": ["inertial required"]}
    result = run("robot", "check", path, "--package-path", f"arm_description={arm.package}", "--require-inertial")
    assert result.exit_code == 1 and "link 'base': has geometry but declares no inertial" in result.stdout


def test_auto_compares_with_the_closer_geometry_and_says_so(tmp_path):
    """A crude collision box and a visual cylinder that is the part: auto takes the visual."""
    m, r, h = 2.0, 0.05, 0.4
    ixx, izz = m * (3 * r * r + h * h) / 12, m * r * r / 2
    path = tmp_path / "crude.urdf"
    path.write_text(f"""<robot name="c"><link name="arm">
      <collision><geometry><box size="0.3 0.3 0.1"/></geometry></collision>
      <visual><geometry><cylinder radius="{r}" length="{h}"/></geometry></visual>
      <inertial><mass value="{m}"/><inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{ixx}" iyz="0" izz="{izz}"/></inertial>
    </link></robot>""")
    robot = load_robot(path)
    (collision,) = check_robot(robot, role="collision")
    (auto,) = check_robot(robot)
    assert not collision.ok and collision.geometry == "collision"
    assert auto.ok and auto.geometry == "visual" and "compared with its visual geometry, the closer match" in auto.notes
    assert auto.implied_density == pytest.approx(m / (np.pi * r * r * h))
    result = run("robot", "check", path, "--from", "collision")
    assert result.exit_code == 1
    assert "(rule: moments; from collision geometry, density " in result.stdout and "tolerance x2)" in result.stdout
    record = json.loads(run("robot", "check", path, "--json").stdout)
    assert record["geometry"] == "visual" and record["tolerance"] == 2.0 and record["status"] == "ok"


def test_a_frame_whose_tensor_is_near_floats_limit_is_checked_not_crashed(tmp_path):
    """A 1 g frame declaring 1e308 moments: summing the tensor with its transpose before scaling
    overflowed to inf, and numpy's eigensolver raised (an internal error, exit 3)."""
    path = tmp_path / "huge.xml"
    path.write_text('<mujoco><worldbody><body name="tip"><inertial pos="0 0 0" mass="0.001" '
                    'fullinertia="1e308 1e308 1e308 -1e308 0 0"/></body></worldbody></mujoco>')
    (check,) = check_robot(load_robot(path))
    assert check.status == "frame"                 # eigenvalues 0, 1e308, 2e308 (inf): none negative
    result = run("robot", "check", path)
    assert result.exit_code == 0, result.output
