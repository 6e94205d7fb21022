"""glTF 2.0 meshes as one set of triangles: every primitive of a mesh, whatever its material.

A glTF mesh is the unit that encloses a solid; its primitives are the pieces its materials cut
it into (glTF 2.0 §3.7.2), so they are joined here into one vertex array and one face array,
and a closed cube in two materials stays one closed cube. Per primitive (§3.7.2.1):

- mode 4 (triangles), 5 (triangle strip) and 6 (triangle fan) make triangles, in the
  specification's vertex order: strip triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), fan
  triangle i is (v_{i+1}, v_{i+2}, v_0); modes 0-3 (points, lines) make none and are counted
  for a warning;
- ``POSITION`` may be float or, as ``KHR_mesh_quantization`` allows, (normalized) integers,
  which are applied (§3.11), not refused;
- morph targets are applied with the node's or the mesh's default ``weights`` (the pose the
  file shows without animation); all zero weights leave the positions as stored;
- a primitive compressed with Draco and no uncompressed fallback is refused by name.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.gltf.data import COMPRESSION, Document, as_float

#: Modes that make no triangles: points, lines, line loop, line strip.
NO_TRIANGLES = (0, 1, 2, 3)
_POSITION_TYPES = ("VEC3",)


class Meshes:
    """The document's meshes as triangles, each built once per set of morph weights."""

    def __init__(self, doc: Document) -> None:
        self.doc = doc
        self._cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        #: Primitives of points or lines met (counted once per mesh).
        self.lines = 0
        #: Primitives without positions.
        self.empty = 0
        #: Triangle lists whose index count is not a multiple of 3.
        self.ragged = 0

    def triangles(self, index: int, path: str, weights=None) -> tuple[np.ndarray, np.ndarray]:
        """Mesh ``index``: its vertices ``(m, 3)`` (float32 as stored when nothing changes them,
        else float64) and faces ``(n, 3)``, over all its primitives: int32 where the vertex
        count allows (half the memory of int64, and the kernels read them as they are), else int64."""
        self.doc.entry("meshes", index, path)      # an index that is no index fails here, by name
        if weights is not None:
            if not all(isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) for w in weights):
                raise self.doc.error(path.rsplit(".", 1)[0] + ".weights", "are not all finite numbers")
            weights = [float(w) for w in weights]
        key = (index, None if weights is None else tuple(weights))
        if key not in self._cache:
            self._cache[key] = self._build(index, path, weights)
        return self._cache[key]

    def _build(self, index: int, path: str, weights) -> tuple[np.ndarray, np.ndarray]:
        doc = self.doc
        mesh = doc.entry("meshes", index, path)
        where = f"meshes[{index}]"
        primitives = doc.items("primitives", mesh, where + ".")
        if weights is None and "weights" in mesh:
            weights = doc.items("weights", mesh, where + ".")
            if not all(isinstance(w, (int, float)) and not isinstance(w, bool) and np.isfinite(w) for w in weights):
                raise doc.error(f"{where}.weights", "are not all finite numbers")
        vertex_sets, face_sets, offset = [], [], 0
        for p, primitive in enumerate(primitives):
            here = f"{where}.primitives[{p}]"
            if not isinstance(primitive, dict):
                raise doc.error(here, "is not a JSON object")
            mode = primitive.get("mode", 4)
            if mode not in (0, 1, 2, 3, 4, 5, 6):
                raise doc.error(f"{here}.mode", f"is {mode!r}, not a glTF primitive mode (0-6)")
            if mode in NO_TRIANGLES:
                self.lines += 1
                continue
            attributes = primitive.get("attributes")
            if not isinstance(attributes, dict):
                raise doc.error(f"{here}.attributes", "is not a JSON object")
            if "POSITION" not in attributes:
                self.empty += 1
                continue
            self._refuse_draco(primitive, attributes, here)
            vertices = self._positions(attributes["POSITION"], f"{here}.attributes.POSITION")
            vertices = self._morphed(vertices, primitive, weights, here)
            corners = self._indices(primitive, len(vertices), here)
            faces = _faces(corners, mode)
            if mode == 4 and len(corners) % 3:
                self.ragged += 1
            vertex_sets.append(vertices)
            face_sets.append(faces.astype(np.int64) + offset if offset else faces)   # no int32 overflow
            offset += len(vertices)
        if not vertex_sets:
            return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int64)
        if len(vertex_sets) == 1:
            return vertex_sets[0], face_sets[0]
        dtype = np.float32 if all(v.dtype == np.float32 for v in vertex_sets) else np.float64
        return np.concatenate([v.astype(dtype, copy=False) for v in vertex_sets]), np.concatenate(face_sets)

    def _refuse_draco(self, primitive: dict, attributes: dict, here: str) -> None:
        extensions = primitive.get("extensions")
        if not isinstance(extensions, dict) or "KHR_draco_mesh_compression" not in extensions:
            return
        accessor = self.doc.entry("accessors", attributes["POSITION"], f"{here}.attributes.POSITION")
        if "bufferView" not in accessor:   # no uncompressed fallback: the positions exist only in Draco
            name = "KHR_draco_mesh_compression"
            raise FormatError(self.doc.where, f"{here} is stored with {name} ({COMPRESSION[name]}), "
                              "which p3d does not decode",
                              "export the glTF without mesh compression (gltf-transform, Blender)")

    def _positions(self, index, path: str) -> np.ndarray:
        values, component, normalized = self.doc.accessor(index, path, _POSITION_TYPES)
        out = as_float(values, component, normalized)
        # A strided view into the buffer: copied once, so that the faces' fancy indexing is fast.
        return np.ascontiguousarray(out)

    def _morphed(self, vertices: np.ndarray, primitive: dict, weights, here: str) -> np.ndarray:
        targets = self.doc.items("targets", primitive, here + ".")
        if not targets or not weights:
            return vertices
        if len(weights) != len(targets) or not all(isinstance(w, (int, float)) and not isinstance(w, bool)
                                                   and np.isfinite(w) for w in weights):
            raise self.doc.error(here, f"has {len(targets)} morph targets but {len(weights)} finite weights")
        out = vertices.astype(np.float64)
        changed = False
        for t, (target, weight) in enumerate(zip(targets, weights)):
            if weight == 0 or not isinstance(target, dict) or "POSITION" not in target:
                continue
            delta, component, normalized = self.doc.accessor(target["POSITION"], f"{here}.targets[{t}].POSITION",
                                                             _POSITION_TYPES)
            if len(delta) != len(out):
                raise self.doc.error(f"{here}.targets[{t}]", f"moves {len(delta)} vertices of {len(out)}")
            out += float(weight) * as_float(delta, component, normalized)
            changed = True
        return out if changed else vertices

    def _indices(self, primitive: dict, vertex_count: int, here: str) -> np.ndarray:
        if "indices" not in primitive:
            return np.arange(vertex_count, dtype=np.int64)
        values, component, _ = self.doc.accessor(primitive["indices"], f"{here}.indices", ("SCALAR",))
        if component not in (5121, 5123, 5125):
            raise self.doc.error(f"{here}.indices", "are not of an unsigned integer type")
        corners = values[:, 0]
        top = int(corners.max()) if len(corners) else 0
        if top >= vertex_count:
            raise self.doc.error(f"{here}.indices", f"name vertex {top}, but the primitive has "
                                 f"{vertex_count} vertices")
        return corners.astype(np.int32 if vertex_count <= 1 << 31 else np.int64)


def _faces(corners: np.ndarray, mode: int) -> np.ndarray:
    """Triangles of ``corners`` drawn in ``mode`` (4, 5 or 6), in the specification's order."""
    if mode == 4:
        return corners[:len(corners) // 3 * 3].reshape(-1, 3)
    n = len(corners) - 2
    if n <= 0:
        return np.zeros((0, 3), np.int64)
    i = np.arange(n)
    if mode == 5:
        odd = i % 2
        return np.stack([corners[i], corners[i + 1 + odd], corners[i + 2 - odd]], axis=1)
    return np.stack([corners[i + 1], corners[i + 2], np.full(n, corners[0])], axis=1)
