"""Fuzz targets: one per reader and one for the scene loader.

Each target takes arbitrary bytes and must end in a result or a ``P3DError``: any other
exception (``IndexError``, ``OverflowError``, ``RecursionError``, ...) is a bug, and so is a
crash or a hang, which the harness that drives the target sees. The same targets serve the
short hypothesis runs of the test suite (``tests/fuzz/test_fuzz.py``) and long coverage-guided
runs with atheris (``tests/fuzz/run_atheris.py``; see docs/fuzzing.md).
"""

from __future__ import annotations

import os
import struct
import tempfile
from pathlib import Path

import numpy as np

from p3d_cli.errors import P3DError
from p3d_cli.io import formats
from p3d_cli.io.raw import RawInput

REPO = Path(__file__).resolve().parents[2]

#: Bytes of the largest fuzz input: enough for every header and a few faces.
MAX_INPUT = 1 << 14


def measure_bytes(data: bytes, fmt: str):
    """Read ``data`` as format ``fmt`` and integrate it, as ``p3d props`` would: the
    ``PropsResult``, or None when p3d refused the input with a ``P3DError``."""
    from p3d_cli.measure.exact import exact_props
    from p3d_cli.measure.solid import Solid

    raw = RawInput("<fuzz>", None, data, len(data))
    try:
        mesh = formats.read(raw, fmt)
        result = exact_props(Solid("<fuzz>", mesh=mesh))
    except P3DError:
        return None
    volume = result.properties.volume
    assert isinstance(volume, float) and np.isfinite(volume), volume
    return result


def load_scene_bytes(data: bytes, steps: int = 0):
    """Parse and solve ``data`` as a scene file (one velocity solve, or ``steps`` steps of
    0.01 s), as ``p3d solve`` would: the ``SolveResult``, or None when p3d refused the scene with
    a ``P3DError``. A numpy RuntimeWarning is a bug too (an overflow must be one RangeError),
    and so is a non-finite number in the result."""
    import warnings

    from p3d_cli.constraints import load_scene, solve_scene

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "scene.yaml")
        with open(path, "wb") as f:
            f.write(data)
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            try:
                result = solve_scene(load_scene(path), steps=steps, dt=0.01 if steps else None)
            except P3DError:
                return None
    _assert_finite_solve(result)
    return result


def _assert_finite_solve(result) -> None:
    numbers = [*result.kinetic_energy, *result.momentum, *result.angular_momentum, result.max_position_error]
    for body in result.bodies:
        numbers += [body.position, body.rotation, body.velocity, body.angular_velocity]
    for c in result.constraints:
        numbers += [c.impulse, c.error, c.position_error]
        if c.angular_impulse is not None:
            numbers.append(c.angular_impulse)
    for value in numbers:
        assert np.all(np.isfinite(value)), value


def seeds(name: str) -> list[bytes]:
    """Valid inputs of each target to mutate from: the bundled samples and examples."""
    samples = REPO / "sample_meshes"
    if name in ("scene", "scene_steps"):
        return [p.read_bytes() for p in sorted((REPO / "examples").glob("*.yaml"))]
    if name == "stl":
        return [(samples / "bracket.stl").read_bytes()[:MAX_INPUT], (samples / "tetrahedron.stl").read_bytes(),
                _binary_stl()]
    if name == "obj":
        return [(samples / "bracket.obj").read_bytes()]
    if name == "off":
        return [(samples / "cube.off").read_bytes()]
    if name == "ply":
        return [_ply("ascii"), _ply("binary_little_endian"), _ply("binary_big_endian")]
    if name in ("gltf", "glb", "3mf"):
        return _scene_seeds(name)
    if name == "dae":
        return [_dae()]
    if name == "amf":
        return [_amf(), _zipped(_amf())]
    if name == "vtp":
        return [_vtp(False), _vtp(True), _legacy_vtk()]
    if name in ROBOT_SEEDS:
        return list(ROBOT_SEEDS[name])
    if name == "robot_fill":
        return [seed for seeds_ in ROBOT_SEEDS.values() for seed in seeds_]
    raise KeyError(name)


def _scene_seeds(name: str) -> list[bytes]:
    """glTF JSON (buffers as data: URIs), GLB, and 3MF model XML: a two-material cube, nodes
    with TRS and matrices, a strip, sparse positions, instancing; components and items."""
    import base64
    import json

    from helpers.gltf_writer import CUBE_FACES, CUBE_VERTICES, TET_FACES, TET_VERTICES, Gltf
    from helpers.threemf_writer import component_object, mesh_object, model

    if name == "3mf":
        return [model([mesh_object(1, CUBE_VERTICES, CUBE_FACES, "cube"),
                       component_object(2, [(1, np.diag([1.0, 1.0, -1.0, 1.0]), None), (1, None, None)])],
                      [(2, None, None), (1, np.eye(4), None)], unit="inch").encode(),
                model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)]).encode()]
    doc = Gltf()
    cube = doc.mesh(doc.primitive(CUBE_VERTICES, CUBE_FACES[:6], index_dtype="uint16"),
                    doc.primitive(CUBE_VERTICES, CUBE_FACES[6:], index_dtype="uint8"))
    child = doc.node(doc.mesh(doc.primitive(CUBE_VERTICES, [4, 0, 5, 1, 6, 2, 7, 3, 4, 0], mode=5)), root=False,
                     matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1])
    doc.node(cube, rotation=[0.0, 0.0, 0.6, 0.8], scale=[1.0, 2.0, 1.0], children=[child])
    ext = {"attributes": {"TRANSLATION": doc.accessor(np.array([[0, 0, 0], [5, 0, 0]]))}}
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES, mode=4)), extensions={"EXT_mesh_gpu_instancing": ext})
    doc.json["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    if name == "glb":
        return [doc.glb()]
    uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(doc.blob)).decode()
    return [json.dumps(doc.document(uri)).encode()]


def threemf_bytes(data: bytes):
    """A 3MF target: ``data`` is a whole package when it starts as a zip does, else the root
    model part's XML, zipped here (so that mutations reach the model reader, not only the zip's
    checksums)."""
    import io
    import zipfile

    if data[:2] != b"PK":
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as archive:
            archive.writestr("3D/3dmodel.model", data)
        data = buffer.getvalue()
    return measure_bytes(data, "3mf")


_TET_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
_TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _binary_stl() -> bytes:
    records = np.zeros(4, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = _TET_V[_TET_F]
    return b"fuzz".ljust(80, b" ") + struct.pack("<I", 4) + records.tobytes()


def _ply(fmt: str) -> bytes:
    head = (f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n").encode()
    if fmt == "ascii":
        body = "".join(f"{x} {y} {z}\n" for x, y, z in _TET_V) + "".join(f"3 {a} {b} {c}\n" for a, b, c in _TET_F)
        return head + body.encode()
    order = "<" if fmt.endswith("little_endian") else ">"
    body = b"".join(struct.pack(order + "3f", *v) for v in _TET_V)
    body += b"".join(struct.pack(order + "B3i", 3, *f) for f in _TET_F)
    return head + body


def _dae() -> bytes:
    """A COLLADA scene: the tetrahedron as triangles and as a polylist, a nested unit, every
    transform element, and an instanced library node."""
    positions = " ".join(str(x) for x in _TET_V.ravel())
    return (f"""<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="0.0254"/></asset><library_geometries><geometry id="g"><asset><unit meter="0.001"/></asset><mesh>
<source id="p"><float_array id="pa" count="12">{positions}</float_array><technique_common><accessor source="#pa"
count="4" stride="3"><param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
</accessor></technique_common></source><vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
<triangles material="a" count="2"><input semantic="VERTEX" source="#v" offset="0"/><input semantic="NORMAL"
source="#p" offset="1"/><p>0 0 2 0 1 0 0 0 1 0 3 0</p></triangles>
<polylist material="b" count="2"><input semantic="VERTEX" source="#v" offset="0"/><vcount>3 3</vcount>
<p>0 3 2 1 2 3</p></polylist><tristrips count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2 3</p>
</tristrips></mesh></geometry></library_geometries><library_nodes><node id="lib"><rotate>1 1 0 30</rotate>
<skew>10 1 0 0 0 1 0</skew><instance_geometry url="#g"/></node></library_nodes><library_visual_scenes>
<visual_scene id="s"><node id="a"><translate>1 2 3</translate><scale>2 1 1</scale><instance_geometry url="#g"/>
<node id="b"><matrix>0 -1 0 0 1 0 0 0 0 0 1 0 0 0 0 1</matrix><lookat>0 0 5 0 0 0 0 1 0</lookat>
<instance_node url="#lib"/></node></node></visual_scene></library_visual_scenes>
<scene><instance_visual_scene url="#s"/></scene></COLLADA>""").encode()


def _amf() -> bytes:
    vertices = "".join(f"<vertex><coordinates><x>{x}</x><y>{y}</y><z>{z}</z></coordinates></vertex>" for x, y, z in _TET_V)
    triangles = "".join(f"<triangle><v1>{a}</v1><v2>{b}</v2><v3>{c}</v3></triangle>" for a, b, c in _TET_F)
    return (f'<?xml version="1.0"?><amf unit="inch"><object id="1"><mesh><vertices>{vertices}</vertices>'
            f'<volume>{triangles[:len(triangles) // 2]}</volume><volume>{triangles[len(triangles) // 2:]}</volume>'
            '</mesh></object><constellation id="c"><instance objectid="1"><deltax>2</deltax><rz>30</rz></instance>'
            '</constellation><constellation id="d"><instance objectid="c"><rx>90</rx></instance>'
            '<instance objectid="1"><deltay>-3</deltay></instance></constellation></amf>').encode()


def _zipped(data: bytes) -> bytes:
    import io
    import zipfile

    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("model.amf", data)
    return buffer.getvalue()


def _vtp(compressed: bool) -> bytes:
    import base64
    import zlib

    def binary(array: np.ndarray) -> bytes:
        data = array.tobytes()
        if not compressed:
            return base64.b64encode(struct.pack("<I", len(data)) + data)
        block = zlib.compress(data)
        return base64.b64encode(struct.pack("<4I", 1, len(data), len(data), len(block))) + base64.b64encode(block)

    arrays = [("Float32", "", _TET_V.astype("<f4")), ("Int64", ' Name="connectivity"', _TET_F.astype("<i8")),
              ("Int64", ' Name="offsets"', np.array([3, 6, 9, 12], dtype="<i8"))]
    out = [f'<DataArray type="{kind}"{name} NumberOfComponents="{3 if not name else 1}" format="binary">'.encode()
           + binary(array) + b"</DataArray>" for kind, name, array in arrays]
    compressor = ' compressor="vtkZLibDataCompressor"' if compressed else ""
    return (f'<?xml version="1.0"?><VTKFile type="PolyData" byte_order="LittleEndian" header_type="UInt32"'
            f'{compressor}><PolyData><Piece NumberOfPoints="4" NumberOfPolys="4"><Points>').encode() + out[0] + \
        b"</Points><Polys>" + out[1] + out[2] + b"</Polys></Piece></PolyData></VTKFile>"


def _legacy_vtk() -> bytes:
    points = " ".join(str(x) for x in _TET_V.ravel())
    cells = "\n".join("3 " + " ".join(map(str, f)) for f in _TET_F)
    return (f"# vtk DataFile Version 3.0\ntet\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n{points}\n"
            "METADATA\nINFORMATION 0\n\n"
            f"POLYGONS 4 16\n{cells}\nTRIANGLE_STRIPS 1 5\n4 1 2 3 0\nPOINT_DATA 4\n").encode()
#: Robot descriptions the robot targets start from: primitives only (no mesh to read), with the
#: constructs fill must keep (empty and end-tagged inertials, comments, CDATA, an entity, CRLF).
ROBOT_SEEDS = {
    "urdf": [b"""<?xml version="1.0"?>
<!DOCTYPE robot [<!ENTITY m "2">]>
<robot name="r" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <!-- <link name="commented"/> -->
  <link name="base"><inertial><origin xyz="0 0 0.1" rpy="0 0 0"/><mass value="&m;"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial>
    <collision><origin xyz="0 0 0.1" rpy="0.1 0.2 0.3"/><geometry><box size="0.1 0.2 0.3"/></geometry></collision>
    <visual><geometry><cylinder radius="0.05" length="0.2"/></geometry></visual></link>
  <link name="arm"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="empty"/>
  <joint name="j" type="revolute"><parent link="base"/><child link="arm"/></joint>
  <gazebo reference="base"><link name="not_a_link"/><![CDATA[ <inertial/> ]]></gazebo>
</robot>
""", b'<robot name="w">\r\n  <link name="a">\r\n    <collision><geometry><capsule radius="0.1" length="0.3"/>'
        b'</geometry></collision>\r\n  </link>\r\n</robot>\r\n'],
    "mjcf": [b"""<mujoco model="m">
  <compiler angle="radian"/>
  <default><geom density="500"/><default class="light"><geom density="100" contype="0" conaffinity="0"/></default></default>
  <worldbody>
    <body name="a" childclass="light">
      <inertial pos="0 0 0" mass="1"
                diaginertia="0.1 0.1 0.1"/>
      <joint type="hinge"/>
      <geom type="box" size="0.1 0.2 0.3" class="main"/>
      <frame pos="0 0 1" euler="0 0 1"><geom type="capsule" fromto="0 0 0 0 0 0.2" size="0.02"/></frame>
      <body name="tip"><inertial pos="0 0 0" mass="0.001" diaginertia="0 0 0"></inertial></body>
      <replicate count="3" offset="0.1 0 0" sep="-"><body name="r"><geom size="0.01" mass="0.2"/></body></replicate>
    </body>
    <body name="b"><geom type="ellipsoid" size="0.1 0.2 0.3" quat="1 0 0 1"/><geom type="cylinder" size="0.1 0.2"/></body>
  </worldbody>
</mujoco>
"""],
    "sdf": [b"""<?xml version="1.0"?>
<sdf version="1.9">
  <model name="m">
    <frame name="f" attached_to="base"><pose>0 0 1 0 0 0.5</pose></frame>
    <link name="base"><pose>1 0 0 0 0 0</pose>
      <inertial><pose relative_to="f">0 0 0 0 0 0</pose><mass>2</mass>
        <inertia><ixx>1</ixx><iyy>1</iyy><izz>1</izz></inertia></inertial>
      <collision name="c"><pose relative_to="__model__">1 0 0.5 0 0 0</pose><geometry><box><size>1 2 3</size></box>
      </geometry></collision>
      <visual name="v"><geometry><cylinder><radius>0.1</radius><length>0.3</length></cylinder></geometry></visual>
    </link>
    <link name="wheel"><collision name="s"><geometry><sphere><radius>0.2</radius></sphere></geometry></collision>
    </link>
    <joint name="j" type="revolute"><parent>base</parent><child>wheel</child><pose>0 0 0 0 0 0</pose></joint>
    <model name="inner"><link name="l"><collision name="e"><geometry><ellipsoid><radii>1 2 3</radii></ellipsoid>
    </geometry></collision></link></model>
  </model>
</sdf>
"""],
}
_ROBOT_FOLDER: list[str] = []


def robot_bytes(data: bytes, kind: str, fill: bool = False):
    """Read ``data`` as a robot description (``kind``: urdf, mjcf, sdf), check it, and with
    ``fill`` fill it from its collision geometry: the checks (or the ``FillResult``), or None
    when p3d refused it with a ``P3DError``. A fill must give a well-formed description of
    the same links, and filling that again must change nothing (fill is idempotent)."""
    from p3d_cli.robots import check_robot, fill_robot, load_robot

    if not _ROBOT_FOLDER:
        _ROBOT_FOLDER.append(tempfile.mkdtemp(prefix="p3d-fuzz-robot-"))
    path = os.path.join(_ROBOT_FOLDER[0], "model." + {"urdf": "urdf", "mjcf": "xml", "sdf": "sdf"}[kind])
    with open(path, "wb") as f:
        f.write(data)
    try:
        robot = load_robot(path)
        checks = check_robot(robot)
        if not fill:
            return checks
        result = fill_robot(robot, density=1000.0, force=True)
    except P3DError:
        return None
    with open(path, "wb") as f:
        f.write(result.data)
    again = load_robot(path)
    assert [link.name for link in again.links] == [link.name for link in robot.links]
    assert fill_robot(again, density=1000.0, force=True).data == result.data
    return result


TARGETS = {
    "stl": lambda data: measure_bytes(data, "stl"),
    "obj": lambda data: measure_bytes(data, "obj"),
    "ply": lambda data: measure_bytes(data, "ply"),
    "off": lambda data: measure_bytes(data, "off"),
    "gltf": lambda data: measure_bytes(data, "gltf"),
    "glb": lambda data: measure_bytes(data, "gltf"),
    "3mf": threemf_bytes,
    "dae": lambda data: measure_bytes(data, "dae"),
    "amf": lambda data: measure_bytes(data, "amf"),
    "vtp": lambda data: measure_bytes(data, "vtp"),
    "scene": load_scene_bytes,
    "scene_steps": lambda data: load_scene_bytes(data, steps=3),
    "urdf": lambda data: robot_bytes(data, "urdf"),
    "mjcf": lambda data: robot_bytes(data, "mjcf"),
    "sdf": lambda data: robot_bytes(data, "sdf"),
    "robot_fill": lambda data: robot_bytes(data, _fill_kind(data), fill=True),
}


def _fill_kind(data: bytes) -> str:
    """The format of a fill target's input, from its root element (any, once mangled: URDF)."""
    head = data[:400]
    return "mjcf" if b"<mujoco" in head else "sdf" if b"<sdf" in head else "urdf"
