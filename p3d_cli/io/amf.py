"""AMF (Additive Manufacturing File Format, ISO/ASTM 52915), plain XML or zipped.

Read here with the standard library's XML parser (expat, which refuses entity expansion
bombs since expat 2.4): trimesh has no AMF loader, and the format is small. What is read:

- ``<amf unit=...>``: millimeter (the default), inch, feet, meter, micron;
- every ``<object>``'s ``<mesh>``: its ``<vertices>`` (decimal text, read as float64) and the
  ``<triangle>`` elements of all its ``<volume>`` elements (curved-triangle ``<edge>`` and
  ``<normal>`` hints are not applied: the flat triangles are measured);
- ``<constellation>``: ``<instance objectid=...>`` with ``deltax/y/z`` and ``rx/ry/rz`` in
  degrees, rotations applied about x, then y, then z (fixed axes), then the translation;
  constellations nest, and only those no other constellation instances are the scene. A file
  without constellations is its objects, each at its own coordinates.
"""

from __future__ import annotations

import io
import zipfile
from xml.etree import ElementTree

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, scene_source, unique_names
from p3d_cli.io.source import MeshSource

#: The ``unit`` values of AMF, in metres (ISO/ASTM 52915 §5.1; "feet" as the standard spells it).
UNITS = {"millimeter": 1e-3, "inch": 0.0254, "feet": 0.3048, "foot": 0.3048, "meter": 1.0, "micron": 1e-6}


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1].lower()


def _children(node, name: str):
    return [child for child in node if _local(child.tag) == name]


def _number(node, name: str, where: str, default: float = 0.0) -> float:
    found = _children(node, name)
    if not found:
        return default
    try:
        return float((found[0].text or "").strip())
    except ValueError:
        raise FormatError(where, f"<{name}> is not a number ({(found[0].text or '').strip()[:40]!r})",
                          "the file is corrupt; export it again") from None


def _xml(raw: RawInput) -> bytes:
    data = raw.read_all()
    if data[:2] != b"PK":
        return data
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as archive:
            names = [n for n in archive.namelist() if not n.endswith("/")]
            chosen = [n for n in names if n.lower().endswith(".amf")] or names
            if not chosen:
                raise zipfile.BadZipFile("the archive is empty")
            return archive.read(chosen[0])
    except (zipfile.BadZipFile, OSError, ValueError, EOFError) as exc:
        raise FormatError(raw.where, f"is not a readable zipped AMF ({exc})", "export it again") from None


def _mesh(obj, where: str) -> tuple[np.ndarray, np.ndarray]:
    meshes = _children(obj, "mesh")
    if not meshes:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    mesh = meshes[0]
    vertices = [(_number(c, "x", where), _number(c, "y", where), _number(c, "z", where))
                for block in _children(mesh, "vertices") for v in _children(block, "vertex")
                for c in _children(v, "coordinates")]
    faces = [(int(_number(t, "v1", where, -1)), int(_number(t, "v2", where, -1)), int(_number(t, "v3", where, -1)))
             for volume in _children(mesh, "volume") for t in _children(volume, "triangle")]
    return np.array(vertices, dtype=np.float64).reshape(-1, 3), np.array(faces, dtype=np.int64).reshape(-1, 3)


def _instance_matrix(instance, where: str) -> np.ndarray:
    from p3d_cli.errors import UsageError
    from p3d_cli.rotation import rotation_from_axis_degrees

    try:
        rx, ry, rz = (rotation_from_axis_degrees(axis, _number(instance, "r" + axis, where)) for axis in "xyz")
    except UsageError as exc:
        raise FormatError(where, f"an instance's rotation is not finite ({exc.what})", "export it again") from None
    matrix = np.eye(4)
    matrix[:3, :3] = rz @ ry @ rx
    matrix[:3, 3] = [_number(instance, k, where) for k in ("deltax", "deltay", "deltaz")]
    return matrix


def _placements(root, objects: dict, where: str) -> list[tuple[str, np.ndarray]]:
    """(object id, whole transform) for every instance in the scene (see the module)."""
    constellations = {c.get("id"): c for c in _children(root, "constellation")}
    if not constellations:
        return [(oid, np.eye(4)) for oid in objects]
    referenced = {i.get("objectid") for c in constellations.values() for i in _children(c, "instance")}
    out: list[tuple[str, np.ndarray]] = []

    def walk(cid: str, outer: np.ndarray, depth: int) -> None:
        if depth > len(constellations):
            raise FormatError(where, f"constellation {cid} instances itself", "the file is corrupt; export it again")
        for instance in _children(constellations[cid], "instance"):
            target = instance.get("objectid")
            matrix = outer @ _instance_matrix(instance, where)
            if target in constellations:
                walk(target, matrix, depth + 1)
            elif target in objects:
                out.append((target, matrix))
            else:
                raise FormatError(where, f"an instance refers to object {target!r}, which the file lacks",
                                  "the file is corrupt; export it again")

    for cid in constellations:
        if cid not in referenced:
            walk(cid, np.eye(4), 0)
    return out


def _name(obj, oid: str) -> str:
    for meta in _children(obj, "metadata"):
        if (meta.get("type") or "").lower() == "name" and (meta.text or "").strip():
            return meta.text.strip()
    return f"object {oid}"


def load(raw: RawInput) -> MeshSource:
    """Read an AMF file (see the module's description).

    Raises
    ------
    FormatError
        Not AMF XML, an unknown unit, a bad number or reference.
    InputError
        No triangles.
    """
    try:
        root = ElementTree.fromstring(_xml(raw))
    except ElementTree.ParseError as exc:
        raise FormatError(raw.where, f"is not valid XML ({exc})", "the file is corrupt; export it again") from None
    if _local(root.tag) != "amf":
        raise FormatError(raw.where, f"is not AMF (its root element is <{_local(root.tag)}>)", "export it as AMF")
    unit = (root.get("unit") or "millimeter").strip().lower()
    if unit not in UNITS:
        raise FormatError(raw.where, f"declares unit {unit!r}, which AMF does not define",
                          "use one of millimeter, inch, feet, meter, micron")
    objects = {obj.get("id"): obj for obj in _children(root, "object")}
    meshes = {oid: _mesh(obj, f"{raw.where}: object {oid}") for oid, obj in objects.items()}
    placed = _placements(root, objects, raw.where)
    names = unique_names([_name(objects[oid], oid) for oid, _ in placed])
    scene = [SceneObject(name, *meshes[oid], matrix) for name, (oid, matrix) in zip(names, placed)]
    return scene_source("amf", raw.where, scene, UNITS[unit], "instances")
