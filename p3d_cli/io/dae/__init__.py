"""COLLADA (``.dae``): the visual meshes of robot description packages, and many exporters'.

Read here over the XML with the standard library's parser (expat, which refuses entity
expansion bombs), following the COLLADA 1.4.1 and 1.5 specifications; nothing of trimesh or
pycollada is used. What is measured:

- **The visual scene's geometry instances.** ``<scene><instance_visual_scene>`` names the
  scene (else the first ``<visual_scene>``); every ``<instance_geometry>`` reached from it
  through ``<node>`` children and ``<instance_node>`` references is one part, placed by the
  product of the node transforms down the way: ``<matrix>`` (row-major), ``<translate>``,
  ``<rotate>`` (axis and degrees), ``<scale>``, ``<skew>`` (degrees, rotation axis, translation
  axis: ``I + tan(angle) t rᵀ`` with both axes normalised, the RenderMan skew as the COLLADA
  conformance tests read it) and ``<lookat>`` (eye, interest, up: the frame that looks from the
  eye down its -z axis at the interest point, y up), each in document order.
- **A geometry is one mesh.** All its triangle primitives together, whatever their materials
  and whether their material bindings resolve (``p3d_cli.io.dae.mesh``).
- **Units by scope.** ``<asset><unit meter=...>`` applies to the element that holds the asset
  and everything inside it, unless a nearer asset says otherwise (COLLADA 1.4.1, "asset"): a
  geometry's positions are in the unit of their ``<source>``'s scope, a node's translations in
  the unit of the node's. The file's unit is the root's; a geometry or node in another unit is
  converted to it, exactly as written (a factor of the ratio). ``<up_axis>`` is not applied:
  coordinates are measured as written, as a URDF ``<mesh>`` places them.

Refused by name, never measured as if absent: skinned and morphed geometry (``<instance_controller>``
of a ``<skin>`` or ``<morph>``: p3d does not pose them), polygons with holes, splines and
B-reps, references into other files, cycles of ``instance_node``, and scenes that place more
than the documented instance and triangle limits (``p3d_cli.io.limits``).
"""

from __future__ import annotations

import math
from typing import Any
from xml.etree import ElementTree

import numpy as np

from p3d_cli.errors import FormatError, InputError, UsageError
from p3d_cli.io.dae.mesh import GeometryMesh, child, children, floats, geometry_mesh, local
from p3d_cli.io.limits import check_instances
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, instance_totals, scene_source, unique_names
from p3d_cli.io.source import MeshSource
from p3d_cli.warning_codes import CodedWarning

_HINT = "the file is corrupt; export it again"
#: The transform elements of a node, applied in document order.
TRANSFORMS = ("matrix", "translate", "rotate", "scale", "skew", "lookat")


class Document:
    """A parsed COLLADA document: elements by id, parents, and units by scope."""

    def __init__(self, root, where: str) -> None:
        self.root = root
        self.where = where
        self.ids: dict[str, Any] = {}
        self.parents: dict[Any, Any] = {}
        for parent in root.iter():
            identifier = parent.get("id")
            if identifier is not None:
                self.ids.setdefault(identifier, parent)
            for element in parent:
                self.parents[element] = parent
        self._units: dict[Any, float] = {}

    def resolve(self, url: str | None, where: str, what: str):
        """The element a ``#id`` URL names.

        Raises
        ------
        FormatError
            No URL, a URL into another file, or an id the file lacks.
        """
        if not url:
            raise FormatError(where, f"a {what} has no URL", _HINT)
        if not url.startswith("#"):
            raise FormatError(where, f"a {what} refers to {url[:80]!r} in another file, which p3d does not open",
                              "export the model as one file")
        found = self.ids.get(url[1:])
        if found is None:
            raise FormatError(where, f"a {what} names {url[:80]!r}, which the file lacks", _HINT)
        return found

    def unit(self, element) -> float:
        """Metres per unit in ``element``'s scope: the nearest ``<asset><unit>`` on it or an
        ancestor, 1 by default (walked up iteratively, remembered per element)."""
        chain = []
        while element is not None and element not in self._units:
            chain.append(element)
            element = self.parents.get(element)
        value = self._units.get(element, 1.0) if element is not None else 1.0
        for element in reversed(chain):
            asset = child(element, "asset")
            unit = child(asset, "unit") if asset is not None else None
            if unit is not None and unit.get("meter") is not None:
                value = _metres(unit.get("meter"), self.where)
            self._units[element] = value
        return value


def _metres(text: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value <= 0:
        raise FormatError(where, f'declares <unit meter="{text[:40]}">, not a number of metres (a positive, '
                          'finite number)', 'write the unit as metres per unit, e.g. <unit meter="0.001"/> '
                          "for millimetres")
    return value


def node_matrix(node, factor: float, where: str) -> np.ndarray:
    """A node's own transform: its transform elements composed in document order, their
    lengths (translations, lookat points) multiplied by ``factor``."""
    out = np.eye(4)
    for element in node:
        kind = local(element.tag)
        if kind in TRANSFORMS:
            out = out @ _transform(kind, element, factor, f"{where}: <{kind}>")
    return out


def _numbers(element, count: int, where: str) -> np.ndarray:
    values = floats(element.text, where, "the element")
    if len(values) != count or not np.all(np.isfinite(values)):
        raise FormatError(where, f"expected {count} finite numbers, found {len(values)}"
                          + ("" if len(values) != count else " (not all finite)"), _HINT)
    return values


def _transform(kind: str, element, factor: float, where: str) -> np.ndarray:
    from p3d_cli.geometry.rotation import rotation_from_axis_degrees

    out = np.eye(4)
    if kind == "matrix":
        out = _numbers(element, 16, where).reshape(4, 4)
        if not np.array_equal(out[3], [0.0, 0.0, 0.0, 1.0]):
            raise FormatError(where, f"its last row is {out[3].tolist()}, not 0 0 0 1 (a projective matrix "
                              "places no solid)", _HINT)
        out[:3, 3] *= factor
    elif kind == "translate":
        out[:3, 3] = _numbers(element, 3, where) * factor
    elif kind == "scale":
        out[:3, :3] = np.diag(_numbers(element, 3, where))
    elif kind == "rotate":
        values = _numbers(element, 4, where)
        if values[3] != 0.0:
            try:
                out[:3, :3] = rotation_from_axis_degrees(values[:3], float(values[3]))
            except UsageError:
                raise FormatError(where, f"rotates about the axis {values[:3].tolist()}, which has no direction",
                                  _HINT) from None
    elif kind == "skew":
        values = _numbers(element, 7, where)
        turn, unit = _unit(values[1:4], where, "rotation axis"), _unit(values[4:7], where, "translation axis")
        if abs(values[0]) >= 90.0:
            raise FormatError(where, f"skews by {values[0]} degrees (|angle| must be under 90)", _HINT)
        out[:3, :3] += math.tan(math.radians(values[0])) * np.outer(unit, turn)
    else:  # lookat
        values = _numbers(element, 9, where)
        eye, interest = values[:3] * factor, values[3:6] * factor
        front = _unit(interest - eye, where, "eye-to-interest direction")
        side = _unit(np.cross(front, values[6:9]), where, "side (up is parallel to the view)")
        out[:3, :3] = np.column_stack([side, np.cross(side, front), -front])
        out[:3, 3] = eye
    return out


def _unit(vector: np.ndarray, where: str, what: str) -> np.ndarray:
    norm = float(np.linalg.norm(vector))
    if not norm > 0.0 or not math.isfinite(norm):
        raise FormatError(where, f"its {what} has no length", _HINT)
    return vector / norm


class _Scene:
    """The node graph of one visual scene: what each node places."""

    def __init__(self, document: Document, where: str) -> None:
        self.document = document
        self.where = where
        self.meshes: dict[Any, GeometryMesh] = {}

    def entries(self, node) -> list[tuple[str, Any]]:
        """``(kind, element)`` for a node's child nodes, instanced nodes and geometries, in order."""
        out = []
        for element in node:
            kind = local(element.tag)
            if kind == "node":
                out.append(("node", element))
            elif kind == "instance_node":
                out.append(("node", self.document.resolve(element.get("url"), self.at(node), "<instance_node>")))
            elif kind == "instance_geometry":
                out.append(("geometry", self.document.resolve(element.get("url"), self.at(node),
                                                              "<instance_geometry>")))
            elif kind == "instance_controller":
                self._refuse_controller(node, element)
        for kind, element in out:
            expected = "node" if kind == "node" else "geometry"
            if local(element.tag) != expected:
                raise FormatError(self.at(node), f"an instance names <{local(element.tag)}> "
                                  f"{element.get('id')!r}, not a <{expected}>", _HINT)
        return out

    def nodes(self, node) -> list:
        return [element for kind, element in self.entries(node) if kind == "node"]

    def own(self, node) -> tuple[int, int]:
        geometries = [element for kind, element in self.entries(node) if kind == "geometry"]
        return len(geometries), sum(len(self.mesh(g).faces) for g in geometries)

    def mesh(self, geometry) -> GeometryMesh:
        found = self.meshes.get(geometry)
        if found is None:
            found = self.meshes[geometry] = geometry_mesh(geometry, self.document, self.where)
        return found

    def at(self, node) -> str:
        """How messages name ``node``."""
        return f"{self.where}: node {(node.get('name') or node.get('id') or '(unnamed)')!r}"

    def _refuse_controller(self, node, element) -> None:
        controller = self.document.resolve(element.get("url"), self.at(node), "<instance_controller>")
        kind = next((local(c.tag) for c in controller if local(c.tag) in ("skin", "morph")), "controller")
        what = {"skin": "a skinned mesh (<instance_controller> of a <skin>)",
                "morph": "a morphed mesh (<instance_controller> of a <morph>)"}.get(kind, "an <instance_controller>")
        raise FormatError(self.at(node), f"places {what} {controller.get('id')!r}, whose pose p3d does not apply",
                          "export the mesh with its pose applied (no armature or shape keys), or export its "
                          "geometry on its own")


def _visual_scene(document: Document, where: str):
    root = document.root
    scene = child(root, "scene")
    instance = child(scene, "instance_visual_scene") if scene is not None else None
    if instance is not None:
        return document.resolve(instance.get("url"), where, "<instance_visual_scene>"), ()
    found = [v for library in children(root, "library_visual_scenes") for v in children(library, "visual_scene")]
    if not found:
        geometries = sum(len(children(lib, "geometry")) for lib in children(root, "library_geometries"))
        raise InputError(where, f"holds no <visual_scene> to place its {geometries} geometries",
                         "export the model with its scene")
    return found[0], ((CodedWarning("the file has no <scene>: its first visual scene is measured", "reader"),)
                      if len(found) > 1 else ())


def placements(document: Document,
               where: str) -> tuple[list[tuple[str, GeometryMesh, np.ndarray]], tuple[CodedWarning, ...]]:
    """``(name, mesh, whole transform)`` for every geometry instance of the visual scene, in
    document order, with the file's unit folded out (transforms map the geometry's own unit to
    the root's), and the warnings.

    Raises
    ------
    FormatError, InputError
    """
    visual, notes = _visual_scene(document, where)
    scene = _Scene(document, where)
    roots = children(visual, "node")
    instances, faces = instance_totals(where, roots, scene.nodes, scene.own, "node")
    check_instances(where, instances, faces, "nodes")
    base = document.unit(document.root)
    found: list[tuple[str, GeometryMesh, np.ndarray]] = []
    stack: list[tuple[str, Any, np.ndarray, str]] = [("node", n, np.eye(4), "") for n in reversed(roots)]
    while stack:
        kind, element, outer, name = stack.pop()
        if kind == "geometry":
            mesh = scene.mesh(element)
            factor = document.unit(mesh.unit_element) / base
            found.append((name, mesh, outer if factor == 1.0 else outer @ np.diag([factor, factor, factor, 1.0])))
            continue
        factor = document.unit(element) / base
        label = element.get("name") or element.get("id") or ""
        whole = outer @ node_matrix(element, factor, scene.at(element))
        entries = scene.entries(element)
        geometries = sum(1 for k, _ in entries if k == "geometry")
        for entry_kind, target in reversed(entries):
            target_name = label or target.get("name") or target.get("id") or ""
            if entry_kind == "geometry" and geometries > 1:
                target_name = f"{label}/{target.get('name') or target.get('id')}" if label else target_name
            stack.append((entry_kind, target, whole, target_name))
    return found, notes


def load(raw: RawInput) -> MeshSource:
    """Read a COLLADA file (see the module's description).

    Raises
    ------
    FormatError
        Not COLLADA, a unit that is not a positive number of metres, a construct p3d refuses
        (controllers, holes, splines, external references, instance cycles, limits), corrupt data.
    InputError
        No triangles.
    """
    try:
        root = ElementTree.fromstring(raw.read_all())
    except ElementTree.ParseError as exc:
        raise FormatError(raw.where, f"is not valid XML ({exc})", _HINT) from None
    if local(root.tag) != "COLLADA":
        raise FormatError(raw.where, f"is not COLLADA (its root element is <{local(root.tag)[:40]}>)",
                          "export the model as COLLADA")
    document = Document(root, raw.where)
    found, notes = placements(document, raw.where)
    if not found:
        raise InputError(raw.where, "its visual scene places no geometry (no <instance_geometry> reached from "
                         "its nodes)", "export the model with its meshes placed in the scene")
    lines = sum(mesh.lines for _, mesh, _ in found)
    if not any(len(mesh.faces) for _, mesh, _ in found):
        raise InputError(raw.where, f"its {len(found)} geometry instances hold no triangles"
                         + (f" (only {lines} line primitives)" if lines else ""),
                         "export the model as a triangle mesh")
    if lines:
        notes += (CodedWarning(f"{lines} line primitives (<lines>, <linestrips>) hold no volume and are left out",
                               "reader"),)
    names = unique_names([name for name, _, _ in found])
    objects = [SceneObject(n, mesh.vertices, mesh.faces, matrix) for n, (_, mesh, matrix) in zip(names, found)]
    return scene_source("dae", raw.where, objects, document.unit(root), "geometry instances", notes)
