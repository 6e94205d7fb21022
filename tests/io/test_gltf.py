"""glTF 2.0 / GLB read by p3d's own reader, construct by construct, against the exact integrals
of the placed triangles (``exact.py``, rational arithmetic). Every file is written here by
``helpers.gltf_writer`` from the specification, with transforms that change the answer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from helpers.exact_check import assert_exact
from helpers.gltf_writer import CUBE_FACES, CUBE_VERTICES, TET_FACES, TET_VERTICES, Gltf, placed, trs
from p3d_cli.cli.main import cli
from p3d_cli.errors import FormatError, InputError

KINDS = ["glb", "gltf", "embedded"]
#: A node transform that changes every integral: turned about an oblique axis, scaled, moved.
AXIS = np.array([1.0, 2.0, 2.0]) / 3.0
TURN = (*(math.sin(0.35) * AXIS), math.cos(0.35))


def save(doc: Gltf, tmp_path, kind: str = "glb"):
    return doc.save(tmp_path / ("m.glb" if kind == "glb" else "m.gltf"), kind)


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("shared", [True, False])
def test_cube_in_two_materials_is_one_closed_cube(tmp_path, kind, shared):
    """Issue 26: one mesh, two primitives (two materials), volume 1 and closed; either both
    primitives index one POSITION accessor, or each has its own copy of the vertices."""
    doc = Gltf()
    doc.json["materials"] = [{"name": "red"}, {"name": "blue"}]
    if shared:
        position = doc.accessor(CUBE_VERTICES)
        halves = [{"attributes": {"POSITION": position}, "indices": doc.accessor(half.reshape(-1), "uint16"),
                   "material": m} for m, half in enumerate((CUBE_FACES[:4], CUBE_FACES[4:]))]
    else:
        halves = [doc.primitive(CUBE_VERTICES, half, material=m) for m, half in enumerate((CUBE_FACES[:4],
                                                                                            CUBE_FACES[4:]))]
    doc.node(doc.mesh(*halves), name="cube")
    result = p3d.props(save(doc, tmp_path, kind))
    assert result.properties.volume == 1.0 and result.facts.closed is True
    assert not result.parts and result.facts.faces == 12
    assert p3d.check(save(doc, tmp_path, kind)).ok


def test_node_tree_with_matrix_and_trs(tmp_path):
    doc = Gltf()
    tet, cube = doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), doc.mesh(doc.primitive(CUBE_VERTICES, CUBE_FACES))
    child_matrix = trs((0.5, -2.0, 1.0), TURN, (1.0, 2.0, 0.5))
    child = doc.node(tet, root=False, name="tip", matrix=child_matrix.T.reshape(-1).tolist())
    doc.node(cube, name="base", translation=[10.0, 0.0, 0.0], rotation=list(TURN), scale=[2.0, 2.0, 2.0],
             children=[child])
    result = p3d.props(save(doc, tmp_path))
    base = trs((10.0, 0.0, 0.0), TURN, (2.0, 2.0, 2.0))
    assert [p.details["name"] for p in result.parts] == ["base", "tip"]
    assert_exact(result.parts[0], placed(CUBE_VERTICES, CUBE_FACES, base))
    assert_exact(result.parts[1], placed(TET_VERTICES, TET_FACES, base @ child_matrix))
    assert_exact(result, np.concatenate([placed(CUBE_VERTICES, CUBE_FACES, base),
                                         placed(TET_VERTICES, TET_FACES, base @ child_matrix)]))


def strip_of(corners):
    """The triangles of a strip, from the glTF specification's words: triangle i is
    (v_i, v_{i+1+i%2}, v_{i+2-i%2})."""
    out = []
    for i in range(len(corners) - 2):
        out.append([corners[i], corners[i + 1 + i % 2], corners[i + 2 - i % 2]])
    return np.array(out)


def test_triangle_strip_and_fan(tmp_path):
    """A closed cube drawn as one strip (the sides) and two fans (top and bottom): issue 26's
    "strip measured 4.1x off"."""
    sides = [4, 0, 5, 1, 6, 2, 7, 3, 4, 0]           # around the four sides, outward
    bottom, top = [0, 3, 2, 1], [4, 5, 6, 7]
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(CUBE_VERTICES, sides, mode=5), doc.primitive(CUBE_VERTICES, bottom, mode=6),
                      doc.primitive(CUBE_VERTICES, top, mode=6)), rotation=list(TURN))
    result = p3d.props(save(doc, tmp_path))
    fan = lambda c: np.array([[c[i + 1], c[i + 2], c[0]] for i in range(len(c) - 2)])  # noqa: E731
    faces = np.concatenate([strip_of(sides), fan(bottom), fan(top)])
    assert result.facts.faces == 12 and result.facts.closed is True
    assert result.properties.volume == pytest.approx(1.0, rel=1e-12)
    assert_exact(result, placed(CUBE_VERTICES, faces, trs(rotation=TURN)))


def test_points_and_lines_make_no_triangles_and_say_so(tmp_path):
    doc = Gltf()
    lines = doc.primitive(CUBE_VERTICES, [0, 1, 1, 2], mode=1)
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES), lines))
    result = p3d.props(save(doc, tmp_path))
    assert any("points or lines (modes 0-3)" in w for w in result.warnings)
    assert_exact(result, placed(TET_VERTICES, TET_FACES))
    only = Gltf()
    only.node(only.mesh(only.primitive(CUBE_VERTICES, mode=0)))
    with pytest.raises(InputError, match="points or lines"):
        p3d.props(save(only, tmp_path))


def test_interleaved_strided_offset_accessors(tmp_path):
    """POSITION interleaved with a normal in one buffer view (byteStride 24), read from byte 12
    of its elements' records, the view itself starting past other data; uint8 indices."""
    doc = Gltf()
    doc.view(b"\x07" * 20)   # something before, so that the view's byteOffset is not 0
    records = np.zeros((len(TET_VERTICES), 6), np.float32)
    records[:, :3] = 99.0    # a "normal" first: the positions start at byte 12 of each record
    records[:, 3:] = TET_VERTICES
    view = doc.view(records.tobytes(), stride=24)
    position = doc.accessor(TET_VERTICES, view=view, offset=12)
    doc.node(doc.mesh({"attributes": {"POSITION": position}, "indices": doc.accessor(TET_FACES.reshape(-1), "uint8")}),
             scale=[1.0, 1.0, -1.0])
    result = p3d.props(save(doc, tmp_path))
    mirror = np.diag([1.0, 1.0, -1.0, 1.0])
    assert result.properties.volume > 0
    assert_exact(result, placed(TET_VERTICES, TET_FACES, mirror))


@pytest.mark.parametrize("with_view", [True, False])
def test_sparse_accessor_substitutes_positions(tmp_path, with_view):
    """Issue 27: sparse accessors were ignored. Base positions (or zeros without a buffer view)
    with vertices 1 and 3 replaced."""
    base = TET_VERTICES.copy()
    base[1] = [100.0, 100.0, 100.0]
    doc = Gltf()
    indices = doc.view(np.array([1, 3], np.uint16).tobytes())
    moved = np.array([[3.0, 0.0, 0.0], [0.0, 0.0, 5.0]], np.float32)
    values = doc.view(moved.tobytes())
    sparse = {"count": 2, "indices": {"bufferView": indices, "componentType": 5123},
              "values": {"bufferView": values}}
    if with_view:
        position = doc.accessor(base, sparse=sparse)
        expected = TET_VERTICES
    else:
        doc.json["accessors"].append({"componentType": 5126, "count": 4, "type": "VEC3", "sparse": sparse})
        position = len(doc.json["accessors"]) - 1
        expected = np.zeros((4, 3), np.float32)
        expected[[1, 3]] = moved
        expected[2] = [0.0, 0.0, 0.0]
    doc.node(doc.mesh({"attributes": {"POSITION": position}, "indices": doc.accessor(TET_FACES.reshape(-1), "uint16")}))
    if with_view:
        assert_exact(p3d.props(save(doc, tmp_path)), placed(expected, TET_FACES))
    else:   # three of four vertices on the z axis or origin: a flat solid of volume 0
        assert p3d.props(save(doc, tmp_path)).properties.volume == 0.0


@pytest.mark.parametrize("dtype, normalized, divisor", [("int16", True, 32767.0), ("uint8", False, 1.0),
                                                        ("uint16", True, 65535.0)])
def test_quantized_positions_are_applied(tmp_path, dtype, normalized, divisor):
    """KHR_mesh_quantization: integer positions, dequantized by the node's scale and offset."""
    stored = (TET_VERTICES * 20).astype(dtype)
    doc = Gltf()
    doc.json["extensionsUsed"] = doc.json["extensionsRequired"] = ["KHR_mesh_quantization"]
    position = doc.accessor(stored, dtype, normalized=normalized)
    doc.node(doc.mesh({"attributes": {"POSITION": position}, "indices": doc.accessor(TET_FACES.reshape(-1), "uint32")}),
             scale=[0.5, 0.25, 2.0], translation=[1.0, 2.0, 3.0])
    result = p3d.props(save(doc, tmp_path))
    values = stored.astype(np.float64) / divisor
    assert_exact(result, placed(values, TET_FACES, trs((1.0, 2.0, 3.0), scale=(0.5, 0.25, 2.0))))


def test_gpu_instancing_places_every_instance(tmp_path):
    """Issue 26: EXT_mesh_gpu_instancing was ignored (59 m³ instead of 343,136). Three instances,
    one mirrored, after a node transform; one part for the node."""
    doc = Gltf()
    doc.json["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    translations = np.array([[0, 0, 0], [10, 0, 0], [0, 20, 0]], np.float32)
    rotations = np.array([[0, 0, 0, 1], TURN, [0, 0, 1, 0]], np.float32)
    scales = np.array([[1, 1, 1], [2, 2, 2], [-1, 1, 1]], np.float32)
    ext = {"attributes": {"TRANSLATION": doc.accessor(translations), "ROTATION": doc.accessor(rotations),
                          "SCALE": doc.accessor(scales)}}
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), translation=[0.0, 0.0, 7.0],
             extensions={"EXT_mesh_gpu_instancing": ext})
    doc.node(doc.mesh(doc.primitive(CUBE_VERTICES, CUBE_FACES)), name="plain")
    result = p3d.props(save(doc, tmp_path))
    node = trs((0.0, 0.0, 7.0))
    expected = [placed(TET_VERTICES, TET_FACES, node @ trs(t, r.astype(np.float64), s))
                for t, r, s in zip(translations.astype(np.float64), rotations, scales.astype(np.float64))]
    assert len(result.parts) == 2 and result.parts[0].facts.faces == 12
    assert all(result.parts[0].properties.volume > 0 for _ in expected)
    assert_exact(result.parts[0], np.concatenate(expected))
    assert_exact(result.parts[1], placed(CUBE_VERTICES, CUBE_FACES))


def test_instances_times_faces_are_bounded(tmp_path, monkeypatch):
    """An instancing bomb made small: 1,000 instances of a tetrahedron against a limit of 3,000
    placed triangles (the same bound trips at a billion)."""
    from p3d_cli.io import limits

    monkeypatch.setattr(limits, "MAX_PLACED_FACES", 3000)
    doc = Gltf()
    ext = {"attributes": {"TRANSLATION": doc.accessor(np.arange(3000, dtype=np.float32).reshape(1000, 3))}}
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), extensions={"EXT_mesh_gpu_instancing": ext})
    with pytest.raises(FormatError, match="4,000 triangles, more than p3d places"):
        p3d.props(save(doc, tmp_path))
    many_nodes = Gltf()
    mesh = many_nodes.mesh(many_nodes.primitive(TET_VERTICES, TET_FACES))
    for i in range(751):
        many_nodes.node(mesh, translation=[float(i), 0.0, 0.0])
    with pytest.raises(FormatError, match="more than p3d places"):
        p3d.props(save(many_nodes, tmp_path))
    monkeypatch.setattr(limits, "MAX_PLACED_FACES", 10 ** 9)
    monkeypatch.setattr(limits, "MAX_INSTANCES", 500)
    with pytest.raises(FormatError, match="501 mesh instances, more than p3d places"):
        p3d.props(save(many_nodes, tmp_path))


def test_morph_target_default_weights_are_applied(tmp_path):
    doc = Gltf()
    delta = np.zeros_like(TET_VERTICES)
    delta[3] = [0.0, 0.0, 2.0]
    primitive = doc.primitive(TET_VERTICES, TET_FACES, targets=[{"POSITION": doc.accessor(delta)}])
    doc.node(doc.mesh(primitive, weights=[0.5]))
    doc.node(doc.mesh(primitive), weights=[0.25], translation=[20.0, 0.0, 0.0])
    result = p3d.props(save(doc, tmp_path))
    assert_exact(result.parts[0], placed(TET_VERTICES + 0.5 * delta, TET_FACES))
    assert_exact(result.parts[1], placed(TET_VERTICES + 0.25 * delta, TET_FACES, trs((20.0, 0.0, 0.0))))


def _skinned(doc: Gltf, joint_translation) -> None:
    joint = doc.node(translation=list(joint_translation), root=True)
    inverse = np.linalg.inv(trs((1.0, 2.0, 3.0))).T.astype(np.float32).reshape(1, 16)
    doc.json["skins"] = [{"joints": [joint], "inverseBindMatrices": doc.accessor(inverse)}]
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), skin=0, translation=[50.0, 0.0, 0.0])


def test_skin_in_bind_pose_is_measured_and_a_posed_one_refused(tmp_path):
    doc = Gltf()
    _skinned(doc, (1.0, 2.0, 3.0))       # joint at its bind transform: the mesh as stored
    assert_exact(p3d.props(save(doc, tmp_path)), placed(TET_VERTICES, TET_FACES))
    posed = Gltf()
    _skinned(posed, (1.0, 2.0, 9.0))
    moved = Gltf()
    joint_a, joint_b = moved.node(root=True), moved.node(translation=[0.0, 4.0, 0.0], root=True)
    identity = np.eye(4, dtype=np.float32).reshape(1, 16)
    inverse = moved.accessor(np.repeat(identity, 2, 0))
    moved.json["skins"] = [{"joints": [joint_a, joint_b], "inverseBindMatrices": inverse}]
    moved.node(moved.mesh(moved.primitive(TET_VERTICES, TET_FACES)), skin=0)
    assert_exact(p3d.props(save(posed, tmp_path)), placed(TET_VERTICES, TET_FACES, trs((0.0, 0.0, 6.0))))
    with pytest.raises(FormatError, match="skinned mesh posed away from its bind pose"):
        p3d.props(save(moved, tmp_path))


def test_without_a_scene(tmp_path):
    """No ``scene``: the first of the file's scenes; no scenes: all root nodes; no nodes: each
    mesh once. Each says so in a warning, none says "holds no triangles"."""
    doc = Gltf()
    tet = doc.mesh(doc.primitive(TET_VERTICES, TET_FACES))
    child = doc.node(tet, root=False, translation=[0.0, 0.0, 1.0])
    doc.node(tet, root=True, translation=[5.0, 0.0, 0.0], children=[child])
    doc.json["scenes"].append({"nodes": [child]})
    del doc.json["scene"]
    result = p3d.props(save(doc, tmp_path))
    assert len(result.parts) == 2 and any("first scene of 2" in w for w in result.warnings)
    del doc.json["scenes"]
    result = p3d.props(save(doc, tmp_path))
    assert len(result.parts) == 2 and any("no scene: all its root nodes" in w for w in result.warnings)
    assert_exact(result.parts[1], placed(TET_VERTICES, TET_FACES, trs((5.0, 0.0, 1.0))))
    doc.json["nodes"] = []
    result = p3d.props(save(doc, tmp_path))
    assert any("no nodes" in w for w in result.warnings)
    assert_exact(result, placed(TET_VERTICES, TET_FACES))


@pytest.mark.parametrize("required, ok", [(["KHR_materials_variants", "KHR_texture_transform"], True),
                                          (["EXT_mesh_gpu_instancing"], True),
                                          (["EXT_made_up_geometry"], False),
                                          (["KHR_draco_mesh_compression"], False),
                                          (["EXT_meshopt_compression"], False)])
def test_required_extensions(tmp_path, required, ok):
    """The specification: a loader refuses a file that requires an extension it does not know;
    extensions that change no geometry are known; compression is refused by name."""
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)))
    doc.json["extensionsUsed"] = doc.json["extensionsRequired"] = required
    path = save(doc, tmp_path)
    if ok:
        assert_exact(p3d.props(path), placed(TET_VERTICES, TET_FACES))
        return
    with pytest.raises(FormatError, match=required[0]):
        p3d.props(path)


def test_unknown_optional_extensions_are_ignored(tmp_path):
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES, extensions={"VENDOR_x": {"a": 1}})),
             extensions={"VENDOR_y": {}})
    doc.json["extensionsUsed"] = ["VENDOR_x", "VENDOR_y"]
    assert_exact(p3d.props(save(doc, tmp_path)), placed(TET_VERTICES, TET_FACES))


def test_optional_draco_reads_the_fallback_and_refuses_without_one(tmp_path):
    doc = Gltf()
    draco = {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES, extensions=draco)))
    doc.json["extensionsUsed"] = ["KHR_draco_mesh_compression"]
    assert_exact(p3d.props(save(doc, tmp_path)), placed(TET_VERTICES, TET_FACES))
    del doc.json["accessors"][0]["bufferView"]       # the positions now exist only in Draco
    with pytest.raises(FormatError, match="KHR_draco_mesh_compression"):
        p3d.props(save(doc, tmp_path))


def test_meshopt_without_fallback_data_is_refused(tmp_path):
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)))
    document = doc.document()
    document["buffers"].append({"byteLength": 1000, "extensions": {"EXT_meshopt_compression": {"fallback": True}}})
    document["bufferViews"][0]["buffer"] = 1
    document["bufferViews"][0]["extensions"] = {"EXT_meshopt_compression": {"buffer": 0, "byteLength": 10}}
    from helpers.gltf_writer import glb_bytes

    path = tmp_path / "m.glb"
    path.write_bytes(glb_bytes(document, bytes(doc.blob)))
    with pytest.raises(FormatError, match="EXT_meshopt_compression"):
        p3d.props(path)


def test_cli_record_and_float32_precision(tmp_path):
    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(CUBE_VERTICES, CUBE_FACES)), name="a")
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)), name="b", translation=[3.0, 0.0, 0.0])
    run = CliRunner().invoke(cli, ["props", str(save(doc, tmp_path)), "--json"])
    assert run.exit_code == 0, run.output
    record = json.loads(run.output)
    assert record["format"] == "gltf" and record["objects"] == "2 nodes"
    assert [p["name"] for p in record["parts"]] == ["a", "b"]
    assert p3d.props(save(doc, tmp_path)).parts[0].facts.coordinate_dtype == "float32"
