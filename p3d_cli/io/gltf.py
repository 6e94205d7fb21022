"""glTF 2.0: ``.gltf`` (JSON, with its buffers beside it or embedded) and ``.glb`` (binary).

Read by trimesh's loader (``p3d_cli.io.trimesh_scene``); every mesh instance is placed by its
node's whole transform. glTF's unit is the metre (glTF 2.0 specification, §3.4 "Coordinate
System and Units"). Positions are float32 and are integrated as stored.

Before trimesh is asked, the JSON is read here for what its loader would get silently wrong:
compressed or quantized positions (``KHR_draco_mesh_compression``, ``EXT_meshopt_compression``,
``KHR_mesh_quantization``: trimesh returns zeros or unscaled integers) and triangle fans
(mode 6, which it skips). Those are refused with a message instead of a wrong number.
"""

from __future__ import annotations

import json
import struct

from p3d_cli.errors import FormatError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import scene_source
from p3d_cli.io.source import MeshSource

GLB_MAGIC = b"glTF"
#: Extensions that change how positions are stored, which p3d cannot integrate as read.
REFUSED_EXTENSIONS = ("KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_mesh_quantization")
_FAN = 6
_NO_VOLUME = (0, 1, 2, 3)


def is_glb(head: bytes) -> bool:
    """The binary container's magic number (glTF 2.0, §4.4.3 "Header")."""
    return head[:4] == GLB_MAGIC


def _json(raw: RawInput) -> dict:
    data = raw.read_all()
    try:
        if is_glb(data):
            if len(data) < 20:
                raise ValueError("shorter than a GLB header")
            length, kind = struct.unpack_from("<I4s", data, 12)
            if kind != b"JSON" or 20 + length > len(data):
                raise ValueError("the first chunk is not a whole JSON chunk")
            text = data[20:20 + length]
        else:
            text = data
        document = json.loads(text.decode("utf-8-sig"))
    except (ValueError, UnicodeDecodeError) as exc:
        raise FormatError(raw.where, f"is not a glTF file ({str(exc).splitlines()[0][:100]})",
                          "the file is corrupt or not glTF; export it again") from None
    if not isinstance(document, dict):
        raise FormatError(raw.where, "is not a glTF file (its JSON is not an object)", "export it again")
    return document


def _refusals(raw: RawInput, document: dict) -> list[str]:
    """Refuse what trimesh would read wrongly; return warnings for what holds no volume."""
    # Only required ones: an optional compression extension comes with uncompressed data too.
    required = document.get("extensionsRequired") or []
    used = [name for name in REFUSED_EXTENSIONS if name in required]
    if used:
        raise FormatError(raw.where, f"its meshes are stored with {used[0]}, which p3d does not decode",
                          "export the glTF without mesh compression or quantization")
    modes = [p.get("mode", 4) for m in document.get("meshes") or [] if isinstance(m, dict)
             for p in m.get("primitives") or [] if isinstance(p, dict)]
    if _FAN in modes:
        raise FormatError(raw.where, "it holds triangle fans (primitive mode 6), which the reader skips",
                          "export the glTF with triangle lists")
    lines = sum(1 for m in modes if m in _NO_VOLUME)
    return [f"{lines} primitives of points or lines hold no volume and are left out"] if lines else []


def load(raw: RawInput) -> MeshSource:
    """Read a glTF 2.0 or GLB file (see the module's description).

    Raises
    ------
    MissingExtraError
        trimesh is not installed.
    FormatError
        Corrupt, compressed, quantized, or holding triangle fans.
    InputError
        No triangles.
    """
    from p3d_cli.io.trimesh_scene import load_scene, scene_objects

    document = _json(raw)
    notes = _refusals(raw, document)
    scene, log = load_scene(raw, "glb" if is_glb(raw.head(4)) else "gltf", "glTF")
    names = [str(n.get("name", "")) for n in document.get("nodes") or [] if isinstance(n, dict)]
    objects, _ = scene_objects(scene, float32=True, order=names)
    return scene_source("gltf", raw.where, objects, 1.0, "nodes", tuple(notes) + log)
