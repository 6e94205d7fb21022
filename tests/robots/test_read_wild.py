"""Issue #25 item 2: load what robotics tools load. Small descriptions that reproduce each real
construct (a generated URDF keeping ``xmlns:xacro``, a ``<gazebo>`` link, a DAE mesh in mm, xacro
with arguments and ``$(find)``, MJCF include, defaults, replicate and per-geom density, SDF
``relative_to`` frames and ``<include merge>``), each checked against the tool that defines it
where one is installed (MuJoCo, xacro)."""

from __future__ import annotations

import numpy as np
import pytest

from p3d_cli.robots import check_robot, fill_robot, load_robot

CUBE = "<geometry><box size='0.1 0.1 0.1'/></geometry>"


def test_a_generated_urdf_that_keeps_the_xacro_namespace_is_a_urdf(tmp_path):
    path = tmp_path / "generated.urdf"
    path.write_text(f'<robot name="r" xmlns:xacro="http://wiki.ros.org/xacro"><link name="a"><collision>{CUBE}'
                    "</collision></link></robot>")
    robot = load_robot(path)
    assert [link.name for link in robot.links] == ["a"]
    assert fill_robot(robot, density=1000.0).links[0].mass == pytest.approx(1.0)


def test_links_in_gazebo_blocks_are_not_robot_links(tmp_path):
    path = tmp_path / "gazebo.urdf"
    path.write_text(f'<robot name="r"><link name="a"><collision>{CUBE}</collision></link>'
                    '<gazebo reference="a"><sensor name="s"><link name="ghost"/></sensor></gazebo>'
                    '<gazebo><plugin filename="x.so"><link name="ghost2"/></plugin></gazebo></robot>')
    assert [link.name for link in load_robot(path).links] == ["a"]


DAE = """<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="millimeter" meter="0.001"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="24">{coords}</float_array>
      <technique_common><accessor source="#pa" count="8" stride="3"><param name="X" type="float"/>
      <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="12"><input semantic="VERTEX" source="#v" offset="0"/><p>{faces}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def test_a_collada_mesh_in_millimetres_is_read_in_metres(tmp_path):
    pytest.importorskip("collada")
    from helpers.robot_arm import box_mesh

    v, f = box_mesh((100.0, 200.0, 300.0), (0.0, 0.0, 0.0))  # mm
    (tmp_path / "part.dae").write_text(DAE.format(coords=" ".join(f"{x:g}" for x in v.ravel()),
                                                  faces=" ".join(map(str, f.ravel()))))
    path = tmp_path / "dae.urdf"
    path.write_text('<robot name="r"><link name="a"><visual><geometry><mesh filename="part.dae"/></geometry>'
                    "</visual></link></robot>")
    (filled,) = fill_robot(load_robot(path), role="visual", density=1000.0).links
    assert filled.status == "filled"
    assert filled.mass == pytest.approx(1000.0 * 0.1 * 0.2 * 0.3, rel=1e-12)
    np.testing.assert_allclose(filled.center, [0.05, 0.1, 0.15], rtol=1e-12)


def test_xacro_with_arguments_and_find(tmp_path, tmp_path_factory):
    pytest.importorskip("xacro")
    package = tmp_path / "my_description"
    (package / "urdf").mkdir(parents=True)
    (package / "urdf" / "parts.xacro").write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:macro name="cube" params="name size">'
        '<link name="${name}"><collision><geometry><box size="${size} ${size} ${size}"/></geometry>'
        "</collision></link></xacro:macro></robot>")
    top = tmp_path / "robot.urdf.xacro"
    top.write_text('<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro"><xacro:arg name="size" '
                   'default="0.1"/><xacro:include filename="$(find my_description)/urdf/parts.xacro"/>'
                   '<xacro:cube name="$(arg prefix)cube" size="$(arg size)"/></robot>')
    robot = load_robot(top, {"my_description": str(package)}, ["prefix:=left_", "size:=0.2"])
    (link,) = robot.links
    assert link.name == "left_cube"
    assert fill_robot(robot, density=1000.0).links[0].mass == pytest.approx(8.0)
    # Not told of, the package is found beside the file (``model.nearby_packages``) ...
    assert [link.name for link in load_robot(top, {}, ["prefix:=left_"]).links] == ["left_cube"]
    # ... and nowhere near it, it is an error that says how to point p3d at it.
    from p3d_cli.errors import InputError

    away = tmp_path_factory.mktemp("elsewhere") / "robot.urdf.xacro"
    away.write_text(top.read_text())
    with pytest.raises(InputError, match=r"\$\(find my_description\) names a package p3d was not told of; give "
                                         "package_paths=my_description=DIR"):
        load_robot(away, {}, ["prefix:=left_"])


MAIN = """<mujoco model="wild">
  <compiler angle="degree" meshdir="meshes"/>
  <include file="shared.xml"/>
  <worldbody>
    <body name="arm" childclass="light">
      <geom type="box" size="0.1 0.2 0.3"/>
      <geom type="sphere" size="0.05" pos="0 0 0.4" class="heavy"/>
      <frame pos="0 0 1" euler="0 90 0">
        <geom type="capsule" fromto="0 0 0 0.2 0 0" size="0.02" mass="0.3"/>
      </frame>
      <replicate count="3" offset="0 0.1 0" euler="0 0 30">
        <geom type="cylinder" size="0.01 0.05" pos="0.2 0 0" density="8000"/>
      </replicate>
    </body>
    <replicate count="4" offset="1 0 0" sep="_">
      <replicate count="2" offset="0 1 0">
        <body name="pod"><geom type="ellipsoid" size="0.1 0.05 0.02"/></body>
      </replicate>
    </replicate>
    <include file="robot.xml"/>
  </worldbody>
</mujoco>
"""
SHARED = """<mujoco>
  <default>
    <geom density="2000"/>
    <default class="light"><geom density="300"/><default class="heavy"><geom density="9000"/></default></default>
  </default>
</mujoco>
"""
ROBOT = """<mujoco><body name="included"><geom type="box" size="0.05 0.05 0.05"/></body></mujoco>"""


def test_mjcf_include_defaults_replicate_frames_and_geom_density_as_mujoco_compiles_them(tmp_path):
    (tmp_path / "shared.xml").write_text(SHARED)
    (tmp_path / "robot.xml").write_text(ROBOT)
    path = tmp_path / "wild.xml"
    path.write_text(MAIN)
    robot = load_robot(path)
    result = fill_robot(robot)  # no inertials: MuJoCo computes every body from its geoms
    ours = {f.link: f for f in result.links}
    mujoco = pytest.importorskip("mujoco")
    from p3d_cli.geometry.rotation import quaternion_matrix

    model = mujoco.MjModel.from_xml_path(str(path))
    names = [model.body(i).name for i in range(1, model.nbody)]
    assert names == [link.name for link in robot.links]
    assert names[1:9] == ["pod0_0", "pod1_0", "pod0_1", "pod1_1", "pod0_2", "pod1_2", "pod0_3", "pod1_3"]
    for name in names:
        b = model.body(name).id
        f = ours[name]
        r = quaternion_matrix(model.body_iquat[b])
        assert f.mass == pytest.approx(model.body_mass[b], rel=1e-9), name
        np.testing.assert_allclose(f.center, model.body_ipos[b], rtol=0, atol=1e-9)
        # MuJoCo computes each geom's inertia in float64 too, but capsules and cylinders by its
        # own formulas (its capsule is exact; its cylinder too): agreement to 1e-6 relative.
        np.testing.assert_allclose(f.inertia, r @ np.diag(model.body_inertia[b]) @ r.T, rtol=0,
                                   atol=1e-6 * np.abs(f.inertia).max())


def test_a_replicated_body_with_an_implausible_inertial_fails_every_copy(tmp_path):
    path = tmp_path / "copies.xml"
    path.write_text('<mujoco><worldbody><replicate count="5" offset="1 0 0"><body name="b">'
                    '<inertial pos="0 0 0" mass="1" diaginertia="1 1 5"/><geom size="0.1"/></body></replicate>'
                    "</worldbody></mujoco>")
    checks = check_robot(load_robot(path))
    assert [c.link for c in checks] == [f"b{i}" for i in range(5)]
    assert all("triangle inequality" in {p.rule for p in c.problems} for c in checks)


SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="m">
    <link name="base"><pose>1 2 3 0 0 0</pose></link>
    <frame name="tool" attached_to="base"><pose relative_to="base">0 0 0.5 0 0 1.5707963267948966</pose></frame>
    <link name="arm">
      <pose relative_to="tool">0 0 1 0 0 0</pose>
      <collision name="c"><pose relative_to="__model__">1 2 4.5 0 0 0</pose>
        <geometry><box><size>0.1 0.2 0.3</size></box></geometry></collision>
      <inertial><pose relative_to="tool">0 0 1 0 0 0</pose><mass>1</mass>
        <inertia><ixx>1</ixx><iyy>2</iyy><izz>3</izz></inertia></inertial>
    </link>
  </model>
</sdf>
"""


def test_sdf_relative_to_frames_are_resolved(tmp_path):
    path = tmp_path / "frames.sdf"
    path.write_text(SDF)
    arm = {link.name: link for link in load_robot(path).links}["arm"]
    # The arm frame is the tool frame (turned 90 degrees about z) moved 1 up: the collision at
    # model (1, 2, 4.5) is at the arm's origin, turned back by -90 degrees about z.
    (geom,) = arm.collision
    assert geom.placement.translation is None or np.allclose(geom.placement.translation, 0, atol=1e-15)
    turn = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(geom.placement.rotation, turn, atol=1e-15)
    np.testing.assert_allclose(arm.inertial.center, [0, 0, 0], atol=1e-15)
    np.testing.assert_allclose(arm.inertial.inertia, np.diag([1.0, 2.0, 3.0]), atol=1e-15)


def test_sdf_include_merge_and_a_frame_cycle(tmp_path):
    models = tmp_path / "models"
    (models / "part").mkdir(parents=True)
    (models / "part" / "model.config").write_text("<model><name>part</name><sdf version='1.9'>part.sdf</sdf></model>")
    (models / "part" / "part.sdf").write_text("<sdf version='1.9'><model name='part'><link name='l'><collision "
                                              "name='c'><geometry><box><size>0.1 0.1 0.1</size></box></geometry>"
                                              "</collision></link></model></sdf>")
    top = tmp_path / "top.sdf"
    top.write_text("<sdf version='1.9'><model name='top'><include merge='true'><uri>model://part</uri></include>"
                   "<include><uri>model://part</uri><name>second</name></include></model></sdf>")
    robot = load_robot(top, {"part": str(models / "part")})
    assert [link.name for link in robot.links] == ["l", "second::l"]
    assert [f.mass for f in fill_robot(robot, density=1000.0).links] == pytest.approx([1.0, 1.0])
    cycle = tmp_path / "cycle.sdf"
    cycle.write_text("<sdf version='1.9'><model name='m'><frame name='a' attached_to='b'/><frame name='b' "
                     "attached_to='a'/><link name='l'><collision name='c'><pose relative_to='a'>0 0 0 0 0 0</pose>"
                     "<geometry><sphere><radius>1</radius></sphere></geometry></collision></link></model></sdf>")
    from p3d_cli.errors import InputError

    with pytest.raises(InputError, match="form a cycle"):
        load_robot(cycle)
