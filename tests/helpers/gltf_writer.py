"""A small glTF 2.0 writer for tests, written from the specification (not from p3d's reader):
buffers, buffer views (with strides and offsets), accessors (with sparse parts), meshes,
nodes and scenes, saved as GLB, as ``.gltf`` + ``.bin``, or as ``.gltf`` with a data: URI."""

from __future__ import annotations

import base64
import json
import struct
from pathlib import Path

import numpy as np

COMPONENT = {np.dtype("int8"): 5120, np.dtype("uint8"): 5121, np.dtype("int16"): 5122, np.dtype("uint16"): 5123,
             np.dtype("uint32"): 5125, np.dtype("float32"): 5126}
TYPE = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}

CUBE_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                          [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float32)
#: Outward, as two triangles per side: bottom, top, front, right, back, left.
CUBE_FACES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                       [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
TET_VERTICES = np.array([[0, 0, 0], [3, 0, 0], [0, 2, 0], [0, 0, 5]], dtype=np.float32)
TET_FACES = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


class Gltf:
    """A glTF document under construction, with one binary buffer."""

    def __init__(self) -> None:
        self.json: dict = {"asset": {"version": "2.0"}, "buffers": [], "bufferViews": [], "accessors": [],
                           "meshes": [], "nodes": [], "scenes": [{"nodes": []}], "scene": 0}
        self.blob = bytearray()

    def view(self, data: bytes, stride: int | None = None, **extra) -> int:
        self.blob += b"\x00" * (-len(self.blob) % 4)
        spec = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data), **extra}
        if stride:
            spec["byteStride"] = stride
        self.blob += data
        self.json["bufferViews"].append(spec)
        return len(self.json["bufferViews"]) - 1

    def accessor(self, values, dtype="float32", normalized=False, view: int | None = None, offset: int = 0,
                 count: int | None = None, **extra) -> int:
        """An accessor over ``values`` (written to a new tightly packed view unless ``view`` is given)."""
        values = np.asarray(values, dtype=dtype)
        values = values.reshape(len(values), -1)
        if view is None and values.size:
            view = self.view(values.tobytes())
        spec = {"componentType": COMPONENT[values.dtype], "count": len(values) if count is None else count,
                "type": TYPE[values.shape[1]], **extra}
        if view is not None:
            spec["bufferView"] = view
        if offset:
            spec["byteOffset"] = offset
        if normalized:
            spec["normalized"] = True
        if values.dtype == np.float32 and values.shape[1] == 3 and values.size:
            spec["min"], spec["max"] = values.min(axis=0).tolist(), values.max(axis=0).tolist()
        self.json["accessors"].append(spec)
        return len(self.json["accessors"]) - 1

    def primitive(self, vertices, faces=None, mode: int | None = None, index_dtype="uint32", **extra) -> dict:
        spec = {"attributes": {"POSITION": self.accessor(vertices)}, **extra}
        if faces is not None:
            spec["indices"] = self.accessor(np.asarray(faces).reshape(-1), index_dtype)
        if mode is not None:
            spec["mode"] = mode
        return spec

    def mesh(self, *primitives: dict, **extra) -> int:
        self.json["meshes"].append({"primitives": list(primitives), **extra})
        return len(self.json["meshes"]) - 1

    def node(self, mesh: int | None = None, root: bool = True, **fields) -> int:
        spec = dict(fields)
        if mesh is not None:
            spec["mesh"] = mesh
        self.json["nodes"].append(spec)
        index = len(self.json["nodes"]) - 1
        if root:
            self.json["scenes"][0]["nodes"].append(index)
        return index

    def document(self, uri: str | None = None) -> dict:
        doc = json.loads(json.dumps(self.json))
        doc["buffers"] = [{"byteLength": len(self.blob)}] if self.blob else []
        if uri is not None and self.blob:
            doc["buffers"][0]["uri"] = uri
        return doc

    def glb(self) -> bytes:
        return glb_bytes(self.document(), bytes(self.blob))

    def save(self, path: Path, kind: str = "glb") -> Path:
        """Write as ``glb``, ``gltf`` (with ``<stem>.bin`` beside it) or ``embedded`` (data: URI)."""
        path = Path(path)
        if kind == "glb":
            path.write_bytes(self.glb())
        elif kind == "gltf":
            (path.parent / (path.stem + ".bin")).write_bytes(bytes(self.blob))
            path.write_text(json.dumps(self.document(path.stem + ".bin")))
        else:
            uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.blob)).decode()
            path.write_text(json.dumps(self.document(uri)))
        return path


def glb_bytes(document: dict, blob: bytes) -> bytes:
    text = json.dumps(document).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<II", len(text), 0x4E4F534A) + text
    if blob:
        blob = blob + b"\x00" * (-len(blob) % 4)
        body += struct.pack("<II", len(blob), 0x004E4942) + blob
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def trs(translation=(0.0, 0.0, 0.0), rotation=(0.0, 0.0, 0.0, 1.0), scale=(1.0, 1.0, 1.0)) -> np.ndarray:
    """T · R · S for a glTF quaternion (x, y, z, w), by trimesh's own quaternion code (w first)."""
    import trimesh

    x, y, z, w = rotation
    out = trimesh.transformations.quaternion_matrix([w, x, y, z])
    out[:3, :3] = out[:3, :3] @ np.diag(scale)
    out[:3, 3] = translation
    return out


def placed(vertices, faces, matrix=np.eye(4)) -> np.ndarray:
    """The triangles of ``vertices[faces]`` through ``matrix`` (float64), reversed if it mirrors."""
    v = np.asarray(vertices, dtype=np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
    f = np.asarray(faces)
    return v[f[:, ::-1] if np.linalg.det(matrix[:3, :3]) < 0 else f]
