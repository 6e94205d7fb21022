"""glTF 2.0: ``.gltf`` (JSON, with its buffers beside it or embedded) and ``.glb`` (binary).

Read here, from the buffers with numpy (``p3d_cli.io.gltf.data``, ``p3d_cli.io.gltf.meshes``),
after the glTF 2.0 specification; no optional library is needed. glTF's unit is the metre
(§3.4). What is measured:

- **the scene**: ``scene`` when the file names one; else its first scene (a warning says so
  when it has several); a file without scenes is all its root nodes (nodes no node lists as a
  child), and a file without nodes is each of its meshes once, unplaced (both with a warning);
- **every node that has a mesh**, placed by its whole transform (``matrix``, or translation,
  rotation and scale, composed down the node tree in float64); each such node is one part,
  named by its ``name``; the node tree is walked without recursion, and a node met twice (a
  cycle, or a child of two parents, which §3.5.3 forbids) is refused;
- **a mesh is all its primitives** (``meshes``), whatever their materials;
- ``EXT_mesh_gpu_instancing``: every instance (its TRANSLATION, ROTATION and SCALE after the
  node's transform), all of one node's instances being that node's part;
- a skinned mesh in its bind pose (every joint's global transform times its inverse bind
  matrix is one and the same matrix) is placed by that matrix; a skin posed otherwise is
  refused (p3d does not blend skins);
- a transform that mirrors reverses the faces (§3.7.4, via ``p3d_cli.io.scene``).

Extensions: ``KHR_mesh_quantization`` and ``EXT_mesh_gpu_instancing`` are applied; Draco and
meshopt compression are refused by name wherever the data exist only compressed; any other
extension in ``extensionsRequired`` is refused, as the specification requires of a loader
that does not know it (§3.12); other extensions (materials, textures, lights) change no
geometry and are ignored. Expansion is bounded by ``p3d_cli.io.limits``.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import limits
from p3d_cli.io.gltf.data import COMPRESSION, Document, as_float, is_glb, read_container
from p3d_cli.io.gltf.meshes import Meshes
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, scene_source, unique_names
from p3d_cli.io.source import MeshSource
from p3d_cli.warning_codes import CodedWarning

__all__ = ["APPLIED", "load", "is_glb"]

#: Extensions p3d applies.
APPLIED = ("EXT_mesh_gpu_instancing", "KHR_mesh_quantization")
#: Prefixes and names of extensions that change no geometry (materials, textures, lights, ...).
_NO_GEOMETRY = ("KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_", "EXT_lights_",
                "KHR_xmp", "KHR_animation_pointer", "KHR_node_visibility", "MSFT_texture_dds",
                "EXT_meshopt_compression", "KHR_meshopt_compression", "KHR_draco_mesh_compression")
_INSTANCE_TYPES = {"TRANSLATION": ("VEC3",), "ROTATION": ("VEC4",), "SCALE": ("VEC3",)}


def _check_extensions(doc: Document) -> None:
    """Refuse a required extension p3d does not apply (§3.12), naming compression outright."""
    required = doc.items("extensionsRequired")
    for name in required:
        if name in COMPRESSION:
            raise FormatError(doc.where, f"its meshes are stored with {name} ({COMPRESSION[name]} compression), "
                              "which p3d does not decode",
                              "export the glTF without mesh compression (gltf-transform, Blender)")
    for name in required:
        if not isinstance(name, str) or not (name in APPLIED or name.startswith(_NO_GEOMETRY)):
            raise FormatError(doc.where, f"it requires the extension {str(name)[:80]!r}, which p3d does not know; "
                              "the glTF specification says a loader must then refuse the file",
                              "export the glTF without that extension")


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """The rotation of unit quaternion ``q = (x, y, z, w)`` (glTF's order), normalised first."""
    norm = float(np.sqrt(np.dot(q, q)))
    if not norm:
        raise ValueError("zero quaternion")
    x, y, z, w = q / norm
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _local(doc: Document, node: dict, where: str) -> np.ndarray:
    """A node's local transform (§3.5.2): its column-major ``matrix``, or T · R · S."""
    if "matrix" in node:
        return doc.numbers(node, "matrix", 16, where, []).reshape(4, 4).T
    out = np.eye(4)
    rotation = doc.numbers(node, "rotation", 4, where, [0.0, 0.0, 0.0, 1.0])
    scale = doc.numbers(node, "scale", 3, where, [1.0, 1.0, 1.0])  # its own error, outside the try
    try:
        out[:3, :3] = quaternion_matrix(rotation) * scale
    except ValueError:
        raise doc.error(f"{where}.rotation", "is the zero quaternion") from None
    out[:3, 3] = doc.numbers(node, "translation", 3, where, [0.0, 0.0, 0.0])
    return out


class _Scene:
    """The node tree: parents, global transforms, and the walk from the scene's roots."""

    def __init__(self, doc: Document) -> None:
        self.doc = doc
        self.nodes = doc.items("nodes")
        self.parent: dict[int, int] = {}
        for i in range(len(self.nodes)):
            node = doc.entry("nodes", i, f"nodes[{i}]")
            for child in doc.items("children", node, f"nodes[{i}]."):
                doc.entry("nodes", child, f"nodes[{i}].children")
                if child in self.parent or child == i:
                    raise doc.error(f"nodes[{i}].children", f"lists node {child}, which already has a parent "
                                    "(the node tree has a cycle or a shared child)")
                self.parent[child] = i
        self._global: dict[int, np.ndarray] = {}

    def global_matrix(self, index: int) -> np.ndarray:
        """Node ``index``'s transform in the scene, composed from its root down (no recursion)."""
        chain = []
        at: int | None = index
        while at is not None and at not in self._global:
            chain.append(at)
            if len(chain) > len(self.nodes):
                raise self.doc.error(f"nodes[{index}]", "is its own ancestor (the node tree has a cycle)")
            at = self.parent.get(at)
        matrix = self._global[at] if at is not None else np.eye(4)
        for i in reversed(chain):
            matrix = matrix @ _local(self.doc, self.nodes[i], f"nodes[{i}]")
            self._global[i] = matrix
        return matrix

    def roots(self) -> tuple[list[int], CodedWarning | None]:
        """The nodes the scene starts from, and a note when the file names no scene."""
        doc = self.doc
        scenes = doc.items("scenes")
        if "scene" in doc.json or scenes:
            chosen = doc.json.get("scene", 0)
            scene = doc.entry("scenes", chosen, "scene")
            note = None
            if "scene" not in doc.json and len(scenes) > 1:
                note = CodedWarning(f"the file names no default scene: its first scene of {len(scenes)} is measured",
                                    "reader")
            nodes = doc.items("nodes", scene, f"scenes[{chosen}].")
            for n in nodes:
                doc.entry("nodes", n, f"scenes[{chosen}].nodes")
            return list(nodes), note
        if self.nodes:
            roots = [i for i in range(len(self.nodes)) if i not in self.parent]
            return roots, CodedWarning("the file has no scene: all its root nodes are measured", "reader")
        return [], None

    def walk(self, roots: list[int]):
        """Every node under ``roots``, depth first in file order; each met once."""
        seen: set[int] = set()
        stack = list(reversed(roots))
        while stack:
            index = stack.pop()
            if index in seen:
                raise self.doc.error(f"nodes[{index}]", "is reached twice from the scene (a cycle, a shared "
                                     "child, or a root listed twice)")
            seen.add(index)
            node = self.nodes[index]
            yield index, node
            stack.extend(reversed(self.doc.items("children", node, f"nodes[{index}].")))


def _instances(doc: Document, node: dict, where: str) -> np.ndarray | None:
    """The ``EXT_mesh_gpu_instancing`` transforms of a node ``(k, 4, 4)``, or None."""
    extensions = node.get("extensions")
    spec = extensions.get("EXT_mesh_gpu_instancing") if isinstance(extensions, dict) else None
    if spec is None:
        return None
    where = f"{where}.extensions.EXT_mesh_gpu_instancing"
    attributes = spec.get("attributes") if isinstance(spec, dict) else None
    if not isinstance(attributes, dict):
        raise doc.error(f"{where}.attributes", "is not a JSON object")
    columns = {}
    for name, types in _INSTANCE_TYPES.items():
        if name in attributes:
            values, component, normalized = doc.accessor(attributes[name], f"{where}.attributes.{name}", types)
            columns[name] = as_float(values, component, normalized).astype(np.float64)
    counts = {len(v) for v in columns.values()}
    if len(counts) > 1:
        raise doc.error(f"{where}.attributes", f"have different counts ({sorted(counts)})")
    count = counts.pop() if counts else 1
    out = np.tile(np.eye(4), (count, 1, 1))
    if "ROTATION" in columns:
        q = columns["ROTATION"]
        norms = np.sqrt((q * q).sum(axis=1))
        if not np.all(np.isfinite(norms)) or np.any(norms == 0):
            raise doc.error(f"{where}.attributes.ROTATION", "holds a zero or non-finite quaternion")
        x, y, z, w = (q / norms[:, None]).T
        out[:, :3, :3] = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                                   2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                                   2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
                                  axis=1).reshape(-1, 3, 3)
    if "SCALE" in columns:
        out[:, :3, :3] *= columns["SCALE"][:, None, :]
    if "TRANSLATION" in columns:
        out[:, :3, 3] = columns["TRANSLATION"]
    return out


def _skin_matrix(doc: Document, scene: _Scene, node: dict, where: str) -> np.ndarray | None:
    """For a skinned node, the one matrix that places its mesh in the bind pose (§3.7.3)."""
    if "skin" not in node:
        return None
    skin = doc.entry("skins", node["skin"], f"{where}.skin")
    here = f"skins[{node['skin']}]"
    joints = doc.items("joints", skin, here + ".")
    if not joints:
        raise doc.error(f"{here}.joints", "is empty")
    if "inverseBindMatrices" in skin:
        values, component, _ = doc.accessor(skin["inverseBindMatrices"], f"{here}.inverseBindMatrices", ("MAT4",))
        if component != 5126 or len(values) < len(joints):
            raise doc.error(f"{here}.inverseBindMatrices", "are not one float matrix per joint")
        inverse = values[:len(joints)].astype(np.float64).reshape(-1, 4, 4).transpose(0, 2, 1)
    else:
        inverse = np.tile(np.eye(4), (len(joints), 1, 1))
    for j in joints:
        doc.entry("nodes", j, f"{here}.joints")
    posed = np.stack([scene.global_matrix(j) for j in joints]) @ inverse
    scale = max(1.0, float(np.abs(posed).max()))
    if not np.all(np.isfinite(posed)) or np.abs(posed - posed[0]).max() > 1e-6 * scale:
        raise FormatError(doc.where, f"{where} holds a skinned mesh posed away from its bind pose; p3d does not "
                          "apply skinning", "export the mesh with the pose applied (Blender: apply the armature)")
    return posed[0]


def _placed_instances(vertices: np.ndarray, faces: np.ndarray, matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One vertex and face array for ``vertices`` placed by each of ``matrices`` (float64), the
    faces of mirroring instances reversed."""
    stacked = np.einsum("kij,mj->kmi", matrices[:, :3, :3], vertices.astype(np.float64)) + matrices[:, None, :3, 3]
    mirror = np.linalg.det(matrices[:, :3, :3]) < 0
    offsets = (np.arange(len(matrices)) * len(vertices))[:, None, None]
    all_faces = np.where(mirror[:, None, None], faces[None, :, ::-1], faces[None]) + offsets
    return stacked.reshape(-1, 3), all_faces.reshape(-1, 3)


def load(raw: RawInput) -> MeshSource:
    """Read a glTF 2.0 or GLB file (see the module's description).

    Raises
    ------
    FormatError
        Corrupt, compressed, a required extension p3d does not know, a skin off its bind
        pose, or an expansion past ``p3d_cli.io.limits``.
    InputError
        No triangles.
    """
    document, binary = read_container(raw)
    doc = Document(raw, document, binary)
    _check_extensions(doc)
    meshes = Meshes(doc)
    scene = _Scene(doc)
    roots, note = scene.roots()
    notes = [note] if note else []
    found: list[tuple[str, np.ndarray, np.ndarray, np.ndarray]] = []
    total = 0
    entries: list[tuple] = []
    if not scene.nodes and "scene" not in document and not doc.items("scenes"):
        entries = [(f"mesh {m}", m, f"meshes[{m}]", None, np.eye(4), None) for m in range(len(doc.items("meshes")))]
        if entries:
            notes.append(CodedWarning("the file has no nodes: each of its meshes is measured once, unplaced", "reader"))
    else:
        for index, node in scene.walk(roots):
            if "mesh" not in node:
                continue
            where = f"nodes[{index}]"
            weights = doc.items("weights", node, where + ".") if "weights" in node else None
            matrix = _skin_matrix(doc, scene, node, where)
            if matrix is None:
                matrix = scene.global_matrix(index)
            name = node.get("name")
            entries.append((str(name) if isinstance(name, str) and name else f"node {index}", node["mesh"],
                            f"{where}.mesh", weights, matrix, _instances(doc, node, where)))
    placed_vertices = placed_instances = 0
    for name, mesh_index, path, weights, matrix, instances in entries:
        vertices, faces = meshes.triangles(mesh_index, path, weights)
        if not len(faces):
            continue
        copies = 1 if instances is None else len(instances)
        total += len(faces) * copies
        placed_vertices += len(vertices) * copies
        placed_instances += copies
        limits.check_instances(raw.where, placed_instances, total, "nodes and GPU instances")
        if placed_vertices > 3 * limits.MAX_PLACED_FACES:
            raise FormatError(raw.where, f"its nodes and GPU instances place {placed_vertices:,} vertices, more than "
                              f"p3d places ({3 * limits.MAX_PLACED_FACES:,})", "measure the meshes apart")
        if instances is not None:
            vertices, faces = _placed_instances(vertices, faces, matrix @ instances)
            matrix = np.eye(4)
        found.append((name, vertices, faces, matrix))
    notes += _warnings(meshes)
    if not found:
        raise InputError(raw.where, _nothing(meshes, entries), "export the model with its meshes as triangles")
    names = unique_names([name for name, _, _, _ in found])
    objects = [SceneObject(n, v, f, m) for n, (_, v, f, m) in zip(names, found)]
    return scene_source("gltf", raw.where, objects, 1.0, "nodes", tuple(notes))


def _warnings(meshes: Meshes) -> list[CodedWarning]:
    out = []
    if meshes.lines:
        out.append(CodedWarning(f"{meshes.lines} primitives of points or lines (modes 0-3) hold no triangles and are "
                                "left out", "reader"))
    if meshes.empty:
        out.append(CodedWarning(f"{meshes.empty} primitives without POSITION hold no triangles and are left out",
                                "reader"))
    if meshes.ragged:
        out.append(CodedWarning(f"{meshes.ragged} triangle lists have an index count that is not a multiple of 3; "
                                "the last 1 or 2 values were ignored", "trailing-data"))
    return out


def _nothing(meshes: Meshes, entries: list) -> str:
    if meshes.lines and not meshes.empty:
        return "the file holds no triangles: its primitives are points or lines (modes 0-3)"
    if not entries:
        return "the file holds no triangles: its scene places no mesh"
    return "the file holds no triangles (no mesh primitive with faces)"
