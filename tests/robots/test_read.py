"""Reading URDF, MJCF and SDF: each link's geometry, measured as an assembly of its geoms, equals
closed forms placed by hand and p3d's own assembly of the same parts; declared inertials are
turned into the link frame."""

from __future__ import annotations

import re

import numpy as np
import pytest

import p3d_cli as p3d
from p3d_cli.errors import InputError
from p3d_cli.robots import load_robot
from p3d_cli.robots.geometry import measure_link
from helpers import robot_oracle as oracle
from helpers.robot_arm import DENSITY, RPY_WEDGE, YAW_BOX


def _props(robot, name):
    link = next(link for link in robot.links if link.name == name)
    geometry = measure_link(link, "collision", robot.path, density=DENSITY)
    assert geometry.solid, geometry.problems
    return geometry.result.properties


def _same(props, expected, rtol=1e-9):
    m, c, i = expected
    assert props.mass == pytest.approx(m, rel=rtol)
    np.testing.assert_allclose(props.center_of_mass, c, rtol=0, atol=rtol * 1.0)
    np.testing.assert_allclose(props.inertia, i, rtol=0, atol=rtol * np.abs(i).max())


@pytest.mark.parametrize("kind", ["urdf", "sdf", "mjcf"])
def test_links_equal_hand_placed_closed_forms(arm, kind, monkeypatch):
    if kind == "sdf":
        monkeypatch.setenv("GZ_SIM_RESOURCE_PATH", str(arm.root))  # model://arm_description/...
    path = getattr(arm, kind)()
    robot = load_robot(path, package_paths=arm.packages if kind == "urdf" else None)
    assert [link.name for link in robot.links] == ["base", "upper"] + (["tool"] if kind != "mjcf" else [])
    _same(_props(robot, "base"), oracle.base_link())
    _same(_props(robot, "upper"), oracle.upper_link(knob="capsule" if kind == "mjcf" else "sphere"))


def test_link_equals_the_assembly_of_the_same_parts(arm, tmp_path):
    """The same parts written as an assembly file (docs/assemblies.md) give the same link."""
    robot = load_robot(arm.urdf(), package_paths=arm.packages)
    wedge = arm.package / "meshes" / "wedge.obj"
    (tmp_path / "upper.yaml").write_text(f"""parts:
  - name: box
    mesh: {arm.root / 'upper.stl'}
    scale: 0.001
    rpy: [0, 0, {YAW_BOX}]
    translate: [0, 0, 0.1]
  - name: wedge
    mesh: {wedge}
    scale: [0.001, -0.001, 0.001]
    rpy: [{RPY_WEDGE[0]}, {RPY_WEDGE[1]}, {RPY_WEDGE[2]}]
    translate: [0.02, 0, 0]
  - name: knob
    shape: sphere:0.03
    translate: [0, 0, 0.4]
""")
    whole = p3d.props(str(tmp_path / "upper.yaml"), density=DENSITY).properties
    mine = _props(robot, "upper")
    _same(mine, (whole.mass, whole.center_of_mass, whole.inertia), rtol=1e-12)


def test_declared_inertial_is_turned_into_the_link_frame(arm, tmp_path):
    text = arm.urdf().read_text().replace('<origin xyz="0.004 0 0.22" rpy="0 0 0"/>',
                                          '<origin xyz="0.004 0 0.22" rpy="0 0 1.5707963267948966"/>')
    path = tmp_path / "turned.urdf"
    path.write_text(text)
    upper = next(link for link in load_robot(path, arm.packages).links if link.name == "upper")
    # ixx and iyy of the inertial frame swap places in the link frame after a quarter turn about z.
    np.testing.assert_allclose(np.diag(upper.inertial.inertia), [0.0227, 0.0225, 0.0011], atol=1e-15)
    np.testing.assert_allclose(upper.inertial.center, [0.004, 0, 0.22])


def test_mjcf_inertial_quat_and_default_classes(arm):
    path = arm.mjcf(upper_inertial='<inertial pos="0 0 0.2" quat="0.7071067811865476 0 0 0.7071067811865476" '
                                   'mass="2" diaginertia="0.01 0.02 0.003"/>')
    robot = load_robot(path)
    upper = robot.links[1]
    np.testing.assert_allclose(np.diag(upper.inertial.inertia), [0.02, 0.01, 0.003], atol=1e-15)
    # The visual class's sphere neither collides nor is collision geometry.
    assert len(upper.collision) == 3 and len(upper.visual) == 1


def test_errors_name_file_link_and_element(arm, tmp_path):
    arm.package.rename(tmp_path / "moved")          # arm_description is found nowhere then
    with pytest.raises(InputError) as info:
        load_robot(arm.urdf())
    message = info.value.message
    # The file and the line of the link element, the link, the element.
    assert re.search(r"arm\.urdf:\d+: link 'upper': collision\[1\]", message)
    assert "mesh package://arm_description/meshes/wedge.obj: no such file" in message
    assert "arm_description=DIR" in message


def test_mjcf_missing_mesh_names_the_body_and_geom(arm):
    (arm.root / "meshes" / "wedge.obj").unlink()
    with pytest.raises(InputError) as info:
        load_robot(arm.mjcf())
    assert re.search(r"arm\.xml:\d+: body 'upper': collision geom\[1\]: mesh 'wedge': ", info.value.message)
    assert "meshes/wedge.obj: no such file" in info.value.message


def test_xacro_without_the_package_is_refused_with_the_install_line(tmp_path, monkeypatch):
    import sys

    from p3d_cli.errors import MissingExtraError

    path = tmp_path / "arm.urdf.xacro"
    path.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="a"><xacro:property name="x" '
                    'value="1"/></robot>')
    monkeypatch.setitem(sys.modules, "xacro", None)  # as if not installed
    for given in (path, tmp_path / "arm.urdf"):
        given.write_text(path.read_text())
        with pytest.raises(MissingExtraError, match=r"xacro package.*extra 'robots': pip install 'xacro>=2.0'"):
            load_robot(given)


@pytest.mark.parametrize("text, what", [
    ("<robot><link", "not well-formed"),
    ("<scene/>", "none of <robot>"),
    ('<robot><link name="a"><collision><geometry><box size="1 2"/></geometry></collision></link></robot>',
     "box size"),
    ('<mujoco><worldbody><body><geom type="mesh" mesh="nope"/></body></worldbody></mujoco>', "not an asset"),
    ('<mujoco><worldbody><body><geom quat="0 0 0 0" size="1"/></body></worldbody></mujoco>', "quat"),
    ('<mujoco><include file="x.xml"/></mujoco>', "x.xml cannot be read"),
    ('<sdf version="1.9"><model name="m"><include><uri>model://x</uri></include></model></sdf>',
     "model model://x: no such file"),
])
def test_bad_descriptions_are_one_error(tmp_path, text, what):
    path = tmp_path / "bad.xml"
    path.write_text(text)
    with pytest.raises(InputError, match=what):
        load_robot(path)


def test_entities_are_read_and_billion_laughs_refused(tmp_path):
    path = tmp_path / "small.urdf"
    path.write_text('<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;">]>'
                    '<robot name="&b;"><link name="&a;"/></robot>')
    assert [link.name for link in load_robot(path).links] == ["a" * 10]
    # Ten levels of ten: 10^10 bytes from a few hundred. expat (>= 2.4) stops the amplification.
    levels = "".join(f'<!ENTITY e{i} "{f"&e{i - 1};" * 10}">' for i in range(1, 10))
    path.write_text(f'<?xml version="1.0"?><!DOCTYPE r [<!ENTITY e0 "laugh">{levels}]><robot name="&e9;"/>')
    with pytest.raises(InputError, match="not well-formed XML"):
        load_robot(path)


@pytest.mark.parametrize("value", ["nan 0 0", "inf 0 0", "1 2", "a b c", "1e400 0 0"])
def test_numbers_must_be_finite_and_counted(arm, tmp_path, value):
    text = arm.urdf().read_text().replace('<origin xyz="0 0 0.4"/>', f'<origin xyz="{value}"/>')
    path = tmp_path / "bad.urdf"
    path.write_text(text)
    with pytest.raises(InputError, match=r"link 'upper': collision\[2\]: origin xyz"):
        load_robot(path, arm.packages)


def _geom_rotations(tmp_path, geoms: str, compiler: str = ""):
    path = tmp_path / "turns.xml"
    path.write_text(f"<mujoco>{compiler}<worldbody><body name='b'>{geoms}</body></worldbody></mujoco>")
    return [g.placement.rotation for g in load_robot(path).links[0].collision]


def test_mjcf_orientations_agree(tmp_path):
    quarter = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    box = 'type="box" size="0.1 0.2 0.3"'
    turns = _geom_rotations(tmp_path, "".join(f"<geom {box} {o}/>" for o in (
        'quat="1 0 0 1"', 'axisangle="0 0 2 90"', 'euler="0 0 90"', 'xyaxes="0 1 0 -3 0 0"')))
    for r in turns:
        np.testing.assert_allclose(r, quarter, atol=1e-15)
    (radian,) = _geom_rotations(tmp_path, f'<geom {box} euler="0 0 1.5707963267948966"/>',
                                '<compiler angle="radian"/>')
    np.testing.assert_allclose(radian, quarter, atol=1e-15)
    # Rotating axes (xyz): Rx then Ry about the new y; fixed axes (XYZ): Rz Ry Rx.
    from helpers.robot_oracle import rx, ry, rz
    (moving,) = _geom_rotations(tmp_path, f'<geom {box} euler="10 20 30"/>')
    (fixed,) = _geom_rotations(tmp_path, f'<geom {box} euler="10 20 30"/>', '<compiler eulerseq="XYZ"/>')
    a, b, c = np.radians([10, 20, 30])
    np.testing.assert_allclose(moving, rx(a) @ ry(b) @ rz(c), atol=1e-15)
    np.testing.assert_allclose(fixed, rz(c) @ ry(b) @ rx(a), atol=1e-15)
    (zaxis,) = _geom_rotations(tmp_path, f'<geom {box} zaxis="1 0 0"/>')
    np.testing.assert_allclose(zaxis @ [0, 0, 1], [1, 0, 0], atol=1e-15)


def test_mjcf_frames_and_childclass(tmp_path):
    path = tmp_path / "frames.xml"
    path.write_text("""<mujoco><default><default class="big"><geom size="0.5"/></default></default>
      <worldbody><body name="b" childclass="big">
        <frame pos="1 0 0" euler="0 0 90"><geom pos="1 0 0"/></frame>
      </body></worldbody></mujoco>""")
    (geom,) = load_robot(path).links[0].collision
    assert geom.thing == "sphere:0.5"
    np.testing.assert_allclose(geom.placement.translation, [1, 1, 0], atol=1e-15)


def test_sdf_pose_forms_agree(tmp_path):
    def inertia(pose: str):
        path = tmp_path / "pose.sdf"
        path.write_text(f"""<sdf version="1.9"><model name="m"><link name="l"><inertial>{pose}<mass>2</mass>
          <inertia><ixx>1</ixx><iyy>2</iyy><izz>3</izz></inertia></inertial></link></model></sdf>""")
        return load_robot(path).links[0].inertial.inertia

    rpy = inertia("<pose>0 0 0 0 0 1.5707963267948966</pose>")
    np.testing.assert_allclose(np.diag(rpy), [2, 1, 3], atol=1e-15)
    np.testing.assert_allclose(inertia('<pose degrees="true">0 0 0 0 0 90</pose>'), rpy, atol=1e-15)
    half = np.sqrt(0.5)
    np.testing.assert_allclose(inertia(f'<pose rotation_format="quat_xyzw">0 0 0 0 0 {half} {half}</pose>'), rpy,
                               atol=1e-15)


def test_a_link_scaled_to_its_mass_scales_its_bounds_too(tmp_path):
    """``mass=`` measures at density 1, then scales every moment of mass to the mass asked for:
    the stated bounds must scale with them (and take the factor's own rounding), or a heavy
    link's inertia error exceeds a bound stated for density 1."""
    from fractions import Fraction

    from helpers.exact_assembly import ExactPart, error_ratios, whole_of

    rng = np.random.default_rng(7)
    corners = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.1, 0.0], [0.0, 0.0, 0.1]])
    corners = corners + rng.uniform(-0.01, 0.01, corners.shape) + [3.1, -2.7, 1.3]
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    triangles = corners[faces]
    (tmp_path / "tet.obj").write_text("".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in corners.tolist())
                                      + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces))
    (tmp_path / "r.urdf").write_text('<robot name="r"><link name="a"><collision><geometry>'
                                     '<mesh filename="tet.obj"/></geometry></collision></link></robot>')
    robot = load_robot(tmp_path / "r.urdf")
    mass = 1.0e6
    light = measure_link(robot.links[0], "collision", robot.path, density=1.0)
    heavy = measure_link(robot.links[0], "collision", robot.path, mass=mass)
    assert heavy.solid and heavy.result.properties.mass == pytest.approx(mass, rel=1e-15)
    k = mass / light.result.properties.mass
    assert np.all(heavy.result.uncertainty["inertia"] >= k * light.result.uncertainty["inertia"])
    assert heavy.result.uncertainty["mass"] >= k * light.result.uncertainty["mass"]
    exact = ExactPart.of_triangles(triangles)
    exact = ExactPart(exact.volume, exact.center, exact.central, Fraction(mass) / exact.volume)
    assert max(error_ratios(heavy.result, whole_of(exact)).values()) <= 1.0


def wedge_path(robot) -> str:
    (upper,) = [link for link in robot.links if link.name == "upper"]
    return [g.thing for g in upper.collision if g.thing.endswith(".obj")][-1]


def test_a_package_beside_the_description_is_found_without_being_named(arm):
    # The arm's folder holds arm_description/ (a workspace's packages side by side).
    assert wedge_path(load_robot(arm.urdf())) == str(arm.package / "meshes" / "wedge.obj")


def test_the_package_a_description_sits_in_is_found_by_its_manifest(arm, tmp_path):
    # A ROS package whose folder is not named after it: its package.xml says its name, and the
    # description inside it finds its own meshes.
    folder = tmp_path / "src" / "arm_pkg-1.2"
    folder.parent.mkdir()
    arm.package.rename(folder)
    (folder / "package.xml").write_text('<?xml version="1.0"?>\n<package format="3">\n  <name> arm_description '
                                        "</name>\n  <version>1.2.0</version>\n</package>\n")
    (folder / "urdf").mkdir()
    for mesh in ("upper.stl", "meshes/upper.stl", "meshes/wedge.obj"):
        (folder / "urdf" / mesh).parent.mkdir(exist_ok=True)
        (folder / "urdf" / mesh).write_bytes((tmp_path / mesh).read_bytes())
    path = folder / "urdf" / "arm.urdf"
    path.write_text(arm.urdf().read_text())
    assert wedge_path(load_robot(path)) == str(folder / "meshes" / "wedge.obj")
    # A folder named in the map comes first.
    other = tmp_path / "mapped"
    (other / "meshes").mkdir(parents=True)
    (other / "meshes" / "wedge.obj").write_bytes((folder / "meshes" / "wedge.obj").read_bytes())
    mapped = load_robot(path, {"arm_description": str(other)})
    assert wedge_path(mapped) == str(other / "meshes" / "wedge.obj")


def test_nearby_packages_are_listed_nearest_first(tmp_path):
    from p3d_cli.robots.model import nearby_packages

    (tmp_path / "ws" / "src" / "robot" / "urdf").mkdir(parents=True)
    (tmp_path / "ws" / "src" / "parts").mkdir()
    (tmp_path / "ws" / "parts").mkdir()
    (tmp_path / "ws" / "src" / "robot" / "package.xml").write_text(
        "<package><name>robot_description</name></package>")
    base = tmp_path / "ws" / "src" / "robot" / "urdf"
    assert nearby_packages("parts", str(base)) == [str(tmp_path / "ws" / "src" / "parts"),
                                                   str(tmp_path / "ws" / "parts")]
    assert nearby_packages("robot_description", str(base)) == [str(tmp_path / "ws" / "src" / "robot")]
    assert nearby_packages("robot", str(base)) == [str(tmp_path / "ws" / "src" / "robot")]
    assert nearby_packages("nothing", str(base)) == []
