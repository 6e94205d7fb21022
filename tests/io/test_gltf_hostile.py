"""Hostile glTF/GLB (issue 27): each case ends in one ``p3d: error:`` line and status 2, never an
internal error, a hang, or a read of what the file does not declare."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

from helpers.gltf_writer import TET_FACES, TET_VERTICES, Gltf, glb_bytes
from helpers.cli_errors import one_error
from p3d_cli.cli.main import cli


def tet() -> Gltf:
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), name="tet")
    return doc


def changed(change) -> bytes:
    doc = tet()
    document = doc.document()
    change(document)
    return glb_bytes(document, bytes(doc.blob))


def _cycle(d):
    d["nodes"] = [{"mesh": 0, "children": [1]}, {"children": [0]}]


def _matrix(value):
    def change(d):
        d["nodes"][0]["matrix"] = value
    return change


CASES = {
    "node cycle": (_cycle, "cycle"),
    "own child": (lambda d: d["nodes"][0].update(children=[0]), "already has a parent"),
    "root listed twice": (lambda d: d["scenes"][0].update(nodes=[0, 0]), "reached twice"),
    "primitives not a list": (lambda d: d["meshes"][0].update(primitives={"a": 1}), "primitives is not a list"),
    "primitive not an object": (lambda d: d["meshes"][0].update(primitives=[7]), "is not a JSON object"),
    "missing mesh": (lambda d: d["nodes"][0].update(mesh=5), "names meshes[5]"),
    "missing child": (lambda d: d["nodes"][0].update(children=[99]), "names nodes[99]"),
    "missing scene": (lambda d: d.update(scene=3), "names scenes[3]"),
    "bool as index": (lambda d: d["nodes"][0].update(mesh=True), "names meshes[True]"),
    "object as index": (lambda d: d["nodes"][0].update(mesh={}), "names meshes[{}]"),
    "list as index": (lambda d: d["nodes"][0].update(mesh=[0]), "names meshes[[0]]"),
    "weights not numbers": (lambda d: d["nodes"][0].update(weights=[[1]]), "weights are not all finite"),
    "nodes not a list": (lambda d: d.update(nodes=5), "nodes is not a list"),
    "unknown mode": (lambda d: d["meshes"][0]["primitives"][0].update(mode=9), "not a glTF primitive mode"),
    "index out of range": (lambda d: d["accessors"][0].update(count=3), "name vertex 3, but the primitive has 3"),
    "huge count": (lambda d: d["accessors"][0].update(count=10 ** 12), "elements"),
    "count past the view": (lambda d: d["accessors"][0].update(count=400), "past the end of its buffer view"),
    "view past the buffer": (lambda d: d["bufferViews"][0].update(byteLength=10 ** 9), "of a buffer of"),
    "odd stride": (lambda d: d["bufferViews"][0].update(byteStride=3), "byteStride"),
    "byteLength past the GLB chunk": (lambda d: d["buffers"][0].update(byteLength=10 ** 15), "declares"),
    "positions as indices type": (lambda d: d["accessors"][0].update(type="SCALAR"), "needs VEC3"),
    "bad component type": (lambda d: d["accessors"][0].update(componentType=5124), "not a glTF component type"),
    "matrix of 15": (_matrix([1.0] * 15), "16 finite numbers"),
    "matrix with a string": (_matrix(["a"] * 16), "16 finite numbers"),
    "zero quaternion": (lambda d: d["nodes"][0].update(rotation=[0, 0, 0, 0]), "zero quaternion"),
    "sparse index out of range": (None, "strictly increasing"),
    "instance counts differ": (None, "different counts"),
    "absolute uri": (lambda d: d["buffers"][0].update(uri="/etc/passwd"), "beside the file only"),
    "http uri": (lambda d: d["buffers"][0].update(uri="http://example.com/a.bin"), "beside the file only"),
    "bad base64": (lambda d: d["buffers"][0].update(uri="data:application/octet-stream;base64,@@@"), "base64"),
    "short data uri": (lambda d: d["buffers"][0].update(uri="data:;base64,AAAA"), "declares"),
    "weights without targets count": (lambda d: (d["meshes"][0]["primitives"][0].update(targets=[{"POSITION": 0}]),
                                                 d["nodes"][0].update(weights=[1.0, 2.0])), "finite weights"),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_damaged_document_is_one_error(tmp_path, name):
    change, match = CASES[name]
    if name == "sparse index out of range":
        doc = tet()
        indices = doc.view(np.array([2, 1], np.uint16).tobytes())
        values = doc.view(np.zeros((2, 3), np.float32).tobytes())
        doc.json["accessors"][0]["sparse"] = {"count": 2, "indices": {"bufferView": indices, "componentType": 5123},
                                              "values": {"bufferView": values}}
        data = doc.glb()
    elif name == "instance counts differ":
        doc = tet()
        ext = {"attributes": {"TRANSLATION": doc.accessor(np.zeros((3, 3))), "SCALE": doc.accessor(np.ones((2, 3)))}}
        doc.json["nodes"][0]["extensions"] = {"EXT_mesh_gpu_instancing": ext}
        data = doc.glb()
    else:
        data = changed(change)
    path = tmp_path / "bad.glb"
    path.write_bytes(data)
    one_error(path, match)


def test_nan_position_is_one_error(tmp_path):
    doc = Gltf()
    vertices = TET_VERTICES.copy()
    vertices[2, 1] = np.nan
    doc.node(doc.mesh(doc.primitive(vertices, TET_FACES)))
    one_error(doc.save(tmp_path / "nan.glb"), "NaN")


def test_deep_json_is_one_error(tmp_path):
    """100,000 nested arrays: the JSON parser's recursion, not p3d's, and still one line."""
    text = '{"asset": {"version": "2.0"}, "extras": ' + "[" * 100_000 + "]" * 100_000 + "}"
    path = tmp_path / "deep.gltf"
    path.write_text(text)
    one_error(path, "nests deeper")


def test_deep_node_chain_is_measured(tmp_path):
    """A valid 20,000-deep node chain (a saved rope): walked without recursion."""
    doc = tet()
    doc.json["nodes"] = [{"children": [i + 1], "translation": [0.001, 0.0, 0.0]} for i in range(20_000)]
    doc.json["nodes"].append({"mesh": 0})
    doc.json["scenes"][0]["nodes"] = [0]
    path = doc.save(tmp_path / "rope.glb")
    run = CliRunner().invoke(cli, ["props", str(path), "--json"])
    assert run.exit_code == 0, run.output
    assert json.loads(run.output)["center_of_mass"][0] == pytest.approx(20.0 + 0.75, rel=1e-9)


@pytest.mark.parametrize("header", [b"glTF\x01\x00\x00\x00" + bytes(12),
                                    b"glTF\x02\x00\x00\x00\xff\xff\x00\x00" + bytes(8),
                                    b"glTF\x02\x00\x00\x00" + bytes(4)])
def test_bad_glb_header_is_one_error(tmp_path, header):
    path = tmp_path / "bad.glb"
    path.write_bytes(header)
    one_error(path, "bad.glb")


def gltf_with_buffer(tmp_path, target: str, length: int = 1000):
    doc = tet()
    document = doc.document(target)
    document["buffers"][0]["byteLength"] = length
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps(document))
    return path


def test_buffer_shorter_than_declared(tmp_path):
    (tmp_path / "short.bin").write_bytes(b"\x00" * 10)
    one_error(gltf_with_buffer(tmp_path, "short.bin", 10 ** 12), "holds 10")


def test_buffer_read_only_to_its_byte_length(tmp_path):
    """A buffer file longer than its byteLength (here by 4 MB of junk) is read to byteLength."""
    doc = tet()
    (tmp_path / "long.bin").write_bytes(bytes(doc.blob) + os.urandom(1 << 22))
    path = tmp_path / "m.gltf"
    path.write_text(json.dumps(doc.document("long.bin")))
    run = CliRunner().invoke(cli, ["props", str(path), "--field", "volume", "--output-units", "m"])
    assert run.exit_code == 0 and float(run.output.split()[-1]) == pytest.approx(5.0, rel=1e-12), run.output


def test_missing_buffer_file(tmp_path):
    one_error(gltf_with_buffer(tmp_path, "nowhere%20near.bin"), "'nowhere near.bin', which cannot be read")


def test_device_as_buffer_is_refused(tmp_path):
    (tmp_path / "zero.bin").symlink_to("/dev/zero")
    one_error(gltf_with_buffer(tmp_path, "zero.bin", 1 << 40), "not a regular file")


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_fifo_as_buffer_is_refused_without_waiting(tmp_path):
    """A FIFO with no writer named as a buffer: refused at once (before, it blocked forever)."""
    os.mkfifo(tmp_path / "pipe.bin")
    path = gltf_with_buffer(tmp_path, "pipe.bin")
    run = subprocess.run([sys.executable, "-m", "p3d_cli", "props", str(path)], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == 2 and "not a regular file" in run.stderr, run.stderr
    assert len(run.stderr.strip().splitlines()) == 1


def test_gltf_from_standard_input_cannot_reach_its_buffer_files(tmp_path):
    path = gltf_with_buffer(tmp_path, "m.bin")
    run = CliRunner().invoke(cli, ["props", "-", "--format", "gltf"], input=path.read_bytes())
    assert run.exit_code == 2 and "standard input cannot reach" in run.output, run.output
