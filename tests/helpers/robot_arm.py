"""A small two-link arm written as URDF, MJCF and SDF, with its meshes (in millimetres).

Links:

- ``base``: one primitive, a cylinder of radius 0.08 m and length 0.1 m, lifted by 0.05 m.
- ``upper``: several meshes, each with its own origin, in mm (scale 0.001): an off-centre box
  ``upper.stl`` turned about z, and the wedge ``wedge.obj`` mirrored in y (scale
  ``0.001 -0.001 0.001``) and turned by roll, pitch and yaw; plus a sphere.
- ``tool``: no geometry, no inertial.

Each description declares plausible inertials that a test may overwrite with a planted fault.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

DENSITY = 2700.0
BOX_MM = (40.0, 60.0, 200.0)
WEDGE_MM = np.array([[0, 0, 0], [50, 0, 0], [0, 30, 0], [0, 0, 80], [50, 0, 80], [0, 30, 80]], dtype=float)
WEDGE_FACES = np.array([[2, 1, 0], [3, 4, 5], [4, 3, 0], [0, 1, 4], [0, 3, 5], [5, 2, 0], [5, 4, 1], [1, 2, 5]])
RPY_WEDGE = (0.1, 0.2, 0.3)
YAW_BOX = 0.3


def box_mesh(size, offset):
    """Vertices and outward faces of an axis-aligned box of ``size`` whose min corner is ``offset``."""
    x, y, z = size
    v = np.array([[i * x, j * y, k * z] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float) + offset
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


def write_stl(path: Path, vertices, faces) -> None:
    tri = vertices[faces].astype(np.float32)
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + struct.pack("<I", len(tri)))
        for t in tri:
            f.write(struct.pack("<3f", 0, 0, 0) + t.tobytes() + b"\0\0")


def write_obj(path: Path, vertices, faces) -> None:
    lines = [f"v {float(a)!r} {float(b)!r} {float(c)!r}" for a, b, c in vertices] + [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    path.write_text("\n".join(lines) + "\n")


URDF = """<?xml version="1.0"?>
<!-- a two-link arm: comments and layout must survive a fill -->
<robot name="arm">
  <link name="base">
    <collision>
      <origin xyz="0 0 0.05" rpy="0 0 0"/>
      <geometry><cylinder radius="0.08" length="0.1"/></geometry>
    </collision>
    <inertial>
      <origin xyz="0 0 0.05"/>
      <mass value="{base_mass}"/>
      <inertia ixx="{base_ixx}" ixy="0" ixz="0" iyy="0.0132" iyz="0" izz="0.0173"/>
    </inertial>
  </link>
  <link name="upper">
    <visual>
      <geometry><sphere radius="0.5"/></geometry>
    </visual>
    <collision>
      <origin xyz="0 0 0.1" rpy="0 0 {yaw}"/>
      <geometry><mesh filename="upper.stl" scale="0.001 0.001 0.001"/></geometry>
    </collision>
    <collision>
      <origin xyz="0.02 0 0" rpy="{r} {p} {y}"/>
      <geometry><mesh filename="package://arm_description/meshes/wedge.obj" scale="0.001 -0.001 0.001"/></geometry>
    </collision>
    <collision>
      <origin xyz="0 0 0.4"/>
      <geometry><sphere radius="0.03"/></geometry>
    </collision>
    <inertial>
      <origin xyz="{upper_com}" rpy="0 0 0"/>
      <mass value="{upper_mass}"/>
      <inertia ixx="0.0225" ixy="0" ixz="0" iyy="0.0227" iyz="0" izz="0.0011"/>
    </inertial>
  </link>
  <link name="tool"/>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <joint name="wrist" type="revolute">
    <parent link="upper"/><child link="tool"/>
    <origin xyz="0 0 0.45"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
</robot>
"""

#: Angles in degrees (MJCF's default); the same placements as the URDF.
MJCF = """<mujoco model="arm">
  <compiler angle="degree" meshdir="meshes"/>
  <!-- defaults: the visual class neither collides nor weighs -->
  <default>
    <geom density="2700"/>
    <default class="visual"><geom contype="0" conaffinity="0" density="0"/></default>
  </default>
  <asset>
    <mesh name="upper" file="upper.stl" scale="0.001 0.001 0.001" {inertia}/>
    <mesh name="wedge" file="wedge.obj" scale="0.001 -0.001 0.001" {inertia}/>
  </asset>
  <worldbody>
    <body name="base">
      <geom type="cylinder" size="0.08 0.05" pos="0 0 0.05"/>
      {base_inertial}
      <body name="upper" pos="0 0 0.1">
        <joint name="shoulder" type="hinge" axis="0 1 0"/>
        <geom class="visual" type="sphere" size="0.5"/>
        <geom type="mesh" mesh="upper" pos="0 0 0.1" euler="0 0 {yaw_deg}"/>
        <geom type="mesh" mesh="wedge" pos="0.02 0 0" euler="{roll_deg} {pitch_deg} {yaw2_deg}"/>
        <geom type="capsule" fromto="0 0 0.4 0.1 0.05 0.45" size="0.02"/>
        {upper_inertial}
      </body>
    </body>
  </worldbody>
</mujoco>
"""

SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="arm">
    <link name="base">
      <collision name="drum">
        <pose>0 0 0.05 0 0 0</pose>
        <geometry><cylinder><radius>0.08</radius><length>0.1</length></cylinder></geometry>
      </collision>
      <inertial>
        <pose>0 0 0.05 0 0 0</pose>
        <mass>{base_mass}</mass>
        <inertia><ixx>{base_ixx}</ixx><iyy>0.0132</iyy><izz>0.0173</izz></inertia>
      </inertial>
    </link>
    <link name="upper">
      <pose>0 0 0.1 0 0 0</pose>
      <collision name="box">
        <pose>0 0 0.1 0 0 {yaw}</pose>
        <geometry><mesh><uri>upper.stl</uri><scale>0.001 0.001 0.001</scale></mesh></geometry>
      </collision>
      <collision name="wedge">
        <pose>0.02 0 0 {r} {p} {y}</pose>
        <geometry><mesh><uri>model://arm_description/meshes/wedge.obj</uri><scale>0.001 -0.001 0.001</scale></mesh></geometry>
      </collision>
      <collision name="knob">
        <pose>0 0 0.4 0 0 0</pose>
        <geometry><sphere><radius>0.03</radius></sphere></geometry>
      </collision>
      <inertial>
        <pose>{upper_com} 0 0 0</pose>
        <mass>{upper_mass}</mass>
        <inertia><ixx>0.0225</ixx><iyy>0.0227</iyy><izz>0.0011</izz></inertia>
      </inertial>
    </link>
    <link name="tool"/>
  </model>
</sdf>
"""

#: Declared values near the geometry's at these masses (not equal: real links are not uniform).
GOOD = {"base_mass": "5.4", "base_ixx": "0.0132", "upper_mass": "1.9", "upper_com": "0.004 0 0.22"}


class Arm:
    """The arm's files in one folder: ``urdf(**faults)``, ``mjcf(...)``, ``sdf(...)`` write a
    description (with the values of ``GOOD`` unless overridden) and return its path."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.package = root / "arm_description"
        (self.package / "meshes").mkdir(parents=True)
        (root / "meshes").mkdir()
        box = box_mesh(BOX_MM, (-20.0, -30.0, 0.0))
        write_stl(root / "upper.stl", *box)
        write_stl(root / "meshes" / "upper.stl", *box)
        write_obj(self.package / "meshes" / "wedge.obj", WEDGE_MM, WEDGE_FACES)
        write_obj(root / "meshes" / "wedge.obj", WEDGE_MM, WEDGE_FACES)
        self.packages = {"arm_description": str(self.package)}

    def urdf(self, name: str = "arm.urdf", **values) -> Path:
        text = URDF.format(**{**GOOD, **values, "yaw": YAW_BOX, "r": RPY_WEDGE[0], "p": RPY_WEDGE[1],
                              "y": RPY_WEDGE[2]})
        path = self.root / name
        path.write_text(text)
        return path

    def sdf(self, name: str = "arm.sdf", **values) -> Path:
        text = SDF.format(**{**GOOD, **values, "yaw": YAW_BOX, "r": RPY_WEDGE[0], "p": RPY_WEDGE[1],
                             "y": RPY_WEDGE[2]})
        path = self.root / name
        path.write_text(text)
        return path

    def mjcf(self, name: str = "arm.xml", base_inertial: str = "", upper_inertial: str = "",
             inertia: str = "") -> Path:
        # MuJoCo's euler="a b c" with eulerseq xyz (rotating axes) is Rx Ry Rz; URDF's rpy is
        # Rz Ry Rx about fixed axes, the same as "XYZ" about fixed axes: so give eulerseq.
        text = MJCF.format(base_inertial=base_inertial, upper_inertial=upper_inertial, inertia=inertia,
                           yaw_deg=np.degrees(YAW_BOX), roll_deg=np.degrees(RPY_WEDGE[0]),
                           pitch_deg=np.degrees(RPY_WEDGE[1]), yaw2_deg=np.degrees(RPY_WEDGE[2]))
        text = text.replace('<compiler angle="degree"', '<compiler angle="degree" eulerseq="XYZ"')
        path = self.root / name
        path.write_text(text)
        return path
