"""p3d's errors are also the builtins a caller catches (``ValueError``, ``OSError``,
``ImportError``), and that changes no exit status and no message: a reader that catches
``ValueError`` around its own parsing must not swallow p3d's error from inside it."""

from __future__ import annotations

import base64
import json
import os
import struct

import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from p3d_cli import errors
from p3d_cli.cli.main import cli

from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl
from helpers.real_meshes import REPO
from helpers.cli_errors import one_error


@pytest.mark.parametrize("cls, builtin", [
    (errors.InputError, ValueError), (errors.FormatError, ValueError), (errors.RangeError, ValueError),
    (errors.UnknownFormatError, ValueError), (errors.SceneError, ValueError), (errors.UsageError, ValueError),
    (errors.SpecError, ValueError), (errors.FieldError, ValueError),
    (errors.ReadError, OSError), (errors.ReadError, errors.InputError), (errors.OutputError, OSError),
    (errors.MissingExtraError, ImportError),
])
def test_each_error_is_the_builtin_a_caller_catches(cls, builtin):
    assert issubclass(cls, builtin) and issubclass(cls, errors.P3DError)
    error = cls("part.stl", "something is wrong", "fix it")
    # the builtin changes nothing a user sees: the message, the exit status, no errno or file name
    assert str(error) == error.message == "part.stl: something is wrong; fix it"
    assert error.args == (error.message,)
    if isinstance(error, OSError):
        assert (error.errno, error.filename, error.strerror) == (None, None, None)


@pytest.mark.parametrize("cls", [errors.CheckFailedError, errors.InternalError])
def test_verdicts_and_bugs_are_no_builtin_error(cls):
    assert not issubclass(cls, (ValueError, OSError, ImportError))


def test_a_missing_file_is_an_oserror_and_a_bad_value_a_valueerror(tmp_path):
    with pytest.raises(OSError) as info:
        p3d.props(str(tmp_path / "missing.stl"))
    assert isinstance(info.value, errors.ReadError) and "no such file" in str(info.value)
    with pytest.raises(OSError, match="is a directory"):
        p3d.props(str(tmp_path))
    with pytest.raises(ValueError, match="no shape named 'cube'"):
        p3d.props("cube:1,2,3")
    with pytest.raises(ValueError, match="exclusive"):
        p3d.props("box", density=1, mass=1)
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0\n")
    with pytest.raises(ValueError) as corrupt:
        p3d.props(str(bad))
    assert isinstance(corrupt.value, errors.FormatError) and not isinstance(corrupt.value, OSError)


def test_exit_statuses_are_unchanged(tmp_path):
    """Missing file, bad format, bad option value: status 2 and one line, as before."""
    runner = CliRunner()
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"solid x\nfacet normal 0 0 0\nouter loop\nvertex 0 0\n")
    unknown = tmp_path / "part.xyz"
    unknown.write_bytes(b"\x00\x01 nothing p3d reads")
    open_box = tmp_path / "open.stl"
    write_ascii_stl(open_box, cube_triangles()[1:])
    for args, status, says in (
        (["props", str(tmp_path / "missing.stl")], 2, "no such file"),
        (["bounds", str(tmp_path / "missing.stl"), "--json"], 2, "no such file"),
        (["check", str(tmp_path / "missing.stl"), "--json"], 2, "no such file"),
        (["props", str(bad)], 2, str(bad)),
        (["props", str(unknown)], 2, str(unknown)),
        (["props", "box", "--density", "1", "--mass", "1"], 2, "both given"),
        (["props", "cube:1,2,3"], 2, "no shape named 'cube'"),
        (["solve", str(tmp_path / "missing.yaml")], 2, "missing.yaml"),
        (["check", str(open_box)], 1, ""),
        (["props", str(REPO / "sample_meshes" / "bracket.stl")], 0, ""),
    ):
        run = runner.invoke(cli, args)
        assert run.exit_code == status, (args, run.output)
        assert "Traceback" not in run.output and says in run.stderr, (args, run.stderr)
        if status == 2:
            assert run.stderr.startswith("p3d: error:") and run.stderr.count("\n") == 1, run.stderr


# Readers catch ValueError around their own parsing; the FormatError they raise in there is a
# ValueError too, and must come out as itself, not wrapped in a second message.

def _gltf_with_scale(scale) -> str:
    corners = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    return json.dumps({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": scale}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(corners).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}]})


VTP_UNKNOWN_FORMAT = """<?xml version="1.0"?>
<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">
<PolyData><Piece NumberOfPoints="3" NumberOfPolys="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="weird">0 0 0 1 0 0 0 1 0</DataArray></Points>
<Polys><DataArray type="Int32" Name="connectivity" format="ascii">0 1 2</DataArray>
<DataArray type="Int32" Name="offsets" format="ascii">3</DataArray></Polys>
</Piece></PolyData></VTKFile>
"""
VTK_HEAD = "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\n"


@pytest.mark.parametrize("name, text, message", [
    ("scale.gltf", _gltf_with_scale([1, "x", 1]), "nodes[0].scale is not a list of 3 finite numbers; the file"),
    ("format.vtp", VTP_UNKNOWN_FORMAT, "format.vtp: a DataArray of unknown format 'weird'; the file is corrupt"),
    ("section.vtk", VTK_HEAD + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nWEIRD 1 4\n3 0 1 2\n",
     "section.vtk: unexpected section 'WEIRD'; the file is corrupt"),
    ("count.vtk", VTK_HEAD + "POINTS x3 float\n0 0 0 1 0 0 0 1 0\n", "count.vtk: the count 'x3' is not an integer; the"),
])
def test_a_readers_own_error_is_not_wrapped_again(tmp_path, name, text, message):
    path = tmp_path / name
    path.write_text(text)
    line = one_error(path, message)
    assert line.count("the file is corrupt") == 1 and "cannot be" not in line, line


def test_a_nonfinite_coordinate_in_bounds_is_said_as_such(tmp_path):
    triangles = cube_triangles()
    triangles[3, 1, 2] = float("inf")
    path = tmp_path / "inf.stl"
    write_binary_stl(path, triangles)
    for thing in (str(path), triangles):
        with pytest.raises(errors.InputError) as info:
            p3d.bounds(thing)
        assert "no faces" not in str(info.value) and "finite" in str(info.value), str(info.value)


def test_an_error_inside_an_atomic_write_is_not_taken_for_a_write_failure(tmp_path):
    from p3d_cli.io.atomic import replacing

    target = tmp_path / "out.txt"
    with pytest.raises(errors.ReadError, match="no such file"):
        with replacing(str(target)) as f:
            f.write(b"half")
            raise errors.ReadError("in.stl", "no such file", "check the path")
    assert not target.exists() and os.listdir(tmp_path) == []


def test_a_zipped_amf_too_large_to_inflate_says_so(tmp_path, monkeypatch):
    import zipfile

    from p3d_cli.io import limits

    monkeypatch.setattr(limits, "MAX_INFLATED", 64)
    path = tmp_path / "part.amf"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("part.amf", "<amf>" + " " * 200 + "</amf>")
    with pytest.raises(errors.FormatError) as info:
        p3d.props(str(path))
    assert "more than p3d inflates" in str(info.value) and "not a readable zipped AMF" not in str(info.value)
