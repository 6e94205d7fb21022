"""Detection, messages and start-up for the scene formats (glTF, 3MF, DAE, AMF, VTK PolyData)."""

from __future__ import annotations

import io
import json
import subprocess
import sys
import zipfile

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

import p3d_cli as p3d
from helpers.meshes import write_binary_stl
from p3d_cli.cli.main import cli
from p3d_cli.errors import FormatError, UnknownFormatError
from p3d_cli.io import detect_format, format_names, is_mesh_path, open_input

BOX = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
LICENCE = "<!-- " + "Licensed under the Apache License, Version 2.0. " * 30 + "-->\n"


@pytest.mark.parametrize("name, expected", [("collada", "dae"), ("DAE", "dae"), ("glb", "gltf"), ("gltf", "gltf"),
                                            ("3mf", "3mf"), ("threemf", "3mf"), ("amf", "amf"), ("vtp", "vtp"),
                                            ("vtk-polydata", "vtp")])
def test_format_names_and_aliases(tmp_path, name, expected):
    path = tmp_path / "x"
    path.write_bytes(b"anything")
    assert detect_format(open_input(str(path)), name) == expected


def test_unknown_format_lists_every_format_value(tmp_path):
    names = format_names()
    for value in ("3mf", "amf", "dae (collada)", "gltf (glb, gltf2)", "obj", "off", "ply", "stl", "vtp"):
        assert value in names
    path = tmp_path / "part.qqq"
    path.write_bytes(b"\x00\x01 not a mesh")
    with pytest.raises(UnknownFormatError, match="dae \\(collada\\)"):
        p3d.props(path)
    with pytest.raises(UnknownFormatError, match="gltf \\(glb"):
        p3d.props(path, format="fbx")


@pytest.mark.parametrize("name, text, match", [
    ("robot.urdf", f'<?xml version="1.0"?>\n{LICENCE}<robot name="arm"><link name="base"/></robot>', "URDF"),
    ("model.xml", '<mujoco model="humanoid"><worldbody/></mujoco>', "MuJoCo MJCF"),
    ("model.sdf", '<?xml version="1.0"?><sdf version="1.7"><model name="m"/></sdf>', "SDF"),
    ("arm.xacro", '<?xml version="1.0"?><robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="a"/>', "URDF"),
])
def test_robot_descriptions_say_what_they_are(tmp_path, name, text, match):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(UnknownFormatError, match=match) as caught:
        p3d.props(path)
    assert "p3d robot" in caught.value.hint and "meshio" not in caught.value.message
    run = CliRunner().invoke(cli, ["props", str(path)])
    assert run.exit_code == 2 and "p3d robot" in run.output and "Traceback" not in run.output


def test_step_says_export_a_mesh(tmp_path):
    path = tmp_path / "part.step"
    path.write_text("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('part'),'2;1');\nENDSEC;\n")
    with pytest.raises(UnknownFormatError, match="STEP") as caught:
        p3d.props(path)
    assert "export a mesh" in caught.value.hint


def test_content_names_the_format_whatever_the_extension(tmp_path):
    glb = tmp_path / "scene.bin"
    glb.write_bytes(trimesh.Scene(BOX).export(file_type="glb"))
    assert p3d.props(glb).facts.format == "gltf"
    dae = tmp_path / "visual.xml"
    dae.write_bytes(BOX.export(file_type="dae"))
    assert detect_format(open_input(str(dae))) == "dae"


def test_glb_from_standard_input():
    data = trimesh.Scene(BOX).export(file_type="glb")
    result = p3d.props("-", stdin=io.BytesIO(data))
    assert result.facts.format == "gltf" and result.properties.volume == pytest.approx(6.0, rel=1e-12)


def test_directory_search_picks_up_scene_formats():
    for name in ("a.glb", "a.gltf", "a.3mf", "a.dae", "a.amf", "a.vtp", "A.GLB"):
        assert is_mesh_path(name), name
    for name in ("robot.urdf", "gltf_buffer_0.bin", "model.sdf"):
        assert not is_mesh_path(name), name


def test_scene_formats_need_no_optional_library(tmp_path, monkeypatch):
    """glTF, 3MF and COLLADA are read by p3d itself: neither trimesh, pycollada, lxml nor
    networkx is needed (each is made unimportable here)."""
    path = tmp_path / "box.glb"
    path.write_bytes(trimesh.Scene(BOX).export(file_type="glb"))
    three = tmp_path / "box.3mf"
    three.write_bytes(trimesh.Scene(BOX).export(file_type="3mf"))
    dae = tmp_path / "box.dae"
    dae.write_bytes(BOX.export(file_type="dae"))
    for module in ("trimesh", "collada", "lxml", "networkx"):
        monkeypatch.setitem(sys.modules, module, None)
    assert p3d.props(path).properties.volume == pytest.approx(6.0, rel=1e-12)
    assert p3d.props(three, output_units="mm").properties.volume == pytest.approx(6.0, rel=1e-12)
    assert p3d.props(dae).properties.volume == pytest.approx(BOX.volume, rel=1e-6)


def _glb_with(document_change) -> bytes:
    data = trimesh.Scene(BOX).export(file_type="glb")
    length = int(np.frombuffer(data[12:16], "<u4")[0])
    document = json.loads(data[20:20 + length])
    document_change(document)
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    rest = data[20 + length:]
    body = np.array([len(text)], "<u4").tobytes() + b"JSON" + text + rest
    return b"glTF" + np.array([2, 12 + len(body)], "<u4").tobytes() + body


@pytest.mark.parametrize("change, match", [
    (lambda d: d.update(extensionsRequired=["KHR_draco_mesh_compression"]), "draco"),
    (lambda d: d.update(extensionsRequired=["EXT_unknown_geometry"]), "does not know"),
])
def test_gltf_that_p3d_cannot_apply_is_refused(tmp_path, change, match):
    path = tmp_path / "bad.glb"
    path.write_bytes(_glb_with(change))
    with pytest.raises(FormatError, match=match):
        p3d.props(path)


@pytest.mark.parametrize("name, data", [
    ("cut.glb", trimesh.Scene(BOX).export(file_type="glb")[:60]),
    ("empty.3mf", None),
    ("bad.dae", b'<?xml version="1.0"?><COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema"><asset>'),
    ("bad.amf", b"<amf><object id='1'><mesh><vertices><vertex><coordinates><x>a</x>"),
    ("notzip.3mf", b"hello, not a zip archive"),
])
def test_corrupt_scene_files_are_one_error(tmp_path, name, data):
    path = tmp_path / name
    if data is None:
        with zipfile.ZipFile(path, "w") as archive:
            archive.writestr("readme.txt", "no model here")
    else:
        path.write_bytes(data)
    run = CliRunner().invoke(cli, ["props", str(path)])
    assert run.exit_code == 2 and "p3d: error:" in run.output and "Traceback" not in run.output, run.output


def test_stl_runs_import_no_scene_library(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, BOX.triangles)
    code = ("import sys, p3d_cli as p3d; p3d.props(sys.argv[1]); "
            "print(sorted(m for m in ('trimesh', 'collada', 'lxml', 'networkx') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
