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

An object is one mesh, all its volumes together whatever their materials. A zipped AMF's
model is inflated to at most the size the archive declares for it and ``MAX_INFLATED``;
instances are counted over the constellation graph before any is placed (``MAX_INSTANCES``,
``p3d_cli.io.limits``), and every vertex index is checked to be a whole number in range.
"""

from __future__ import annotations

import io
import zipfile
import zlib
from xml.etree import ElementTree

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.dae.mesh import floats, indices
from p3d_cli.io.limits import check_instances, read_member
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, instance_totals, scene_source, unique_names
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
            # (not ZipInfo.is_dir, which fails on an empty member name)
            members = [m for m in archive.infolist() if m.filename and not m.filename.endswith("/")]
            chosen = [m for m in members if m.filename.lower().endswith(".amf")] or members
            if not chosen:
                raise zipfile.BadZipFile("the archive is empty")
            return read_member(raw.where, archive, chosen[0], f"the zipped AMF's {chosen[0].filename[:60]!r}")
    except FormatError:
        raise  # read_member's own, a ValueError too: as it is
    except (zipfile.BadZipFile, zlib.error, OSError, ValueError, EOFError, NotImplementedError, RuntimeError) as exc:
        raise FormatError(raw.where, f"is not a readable zipped AMF ({str(exc)[:120]})", "export it again") from None


def _mesh(obj, where: str) -> tuple[np.ndarray, np.ndarray]:
    """An object's vertices and the triangles of all its volumes (whatever their materials)."""
    meshes = _children(obj, "mesh")
    if not meshes:
        return np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
    mesh = meshes[0]
    coordinates = [c for block in _children(mesh, "vertices") for v in _children(block, "vertex")
                   for c in _children(v, "coordinates")]
    text = " ".join(_text(c, axis) for c in coordinates for axis in "xyz")
    values = floats(text, where, "the vertex coordinates")
    if len(values) != 3 * len(coordinates):
        raise FormatError(where, "a vertex coordinate holds more than one number",
                          "the file is corrupt; export it again")
    vertices = values.reshape(-1, 3)
    found = [t for volume in _children(mesh, "volume") for t in _children(volume, "triangle")]
    corners = " ".join(_text(t, k, None) or _missing(where, k) for t in found for k in ("v1", "v2", "v3"))
    values = indices(corners, where, "the triangles")
    if len(values) != 3 * len(found):
        raise FormatError(where, "a triangle's v1, v2 or v3 holds more than one index",
                          "the file is corrupt; export it again")
    faces = values.reshape(-1, 3)
    if len(faces) and faces.max() >= len(vertices):
        raise FormatError(where, f"a triangle refers to vertex {int(faces.max())}, but the object has "
                          f"{len(vertices)}", "the file is corrupt; export it again")
    return vertices, faces


def _text(node, name: str, default: str | None = "0") -> str:
    """The text of ``node``'s first ``name`` child (``default`` when there is none)."""
    found = _children(node, name)
    if not found:
        return default or ""
    text = (found[0].text or "").strip()
    if not text:
        return default or ""
    return text


def _missing(where: str, name: str) -> str:
    raise FormatError(where, f"a triangle has no <{name}>", "the file is corrupt; export it again")


def _instance_matrix(instance, where: str) -> np.ndarray:
    from p3d_cli.errors import UsageError
    from p3d_cli.geometry.rotation import rotation_from_axis_degrees

    try:
        rx, ry, rz = (rotation_from_axis_degrees(axis, _number(instance, "r" + axis, where)) for axis in "xyz")
    except UsageError as exc:
        raise FormatError(where, f"an instance's rotation is not finite ({exc.what})", "export it again") from None
    matrix = np.eye(4)
    matrix[:3, :3] = rz @ ry @ rx
    matrix[:3, 3] = [_number(instance, k, where) for k in ("deltax", "deltay", "deltaz")]
    if not np.all(np.isfinite(matrix)):
        raise FormatError(where, "an instance's displacement is not finite", "export it again")
    return matrix


def _placements(root, objects: dict, meshes: dict, where: str) -> list[tuple[str, np.ndarray]]:
    """(object id, whole transform) for every instance in the scene (see the module), counted
    over the constellation graph before any is placed, and walked without recursion."""
    constellations = {c.get("id"): c for c in _children(root, "constellation")}
    if not constellations:
        return [(oid, np.eye(4)) for oid in objects]
    for c in constellations.values():
        for instance in _children(c, "instance"):
            target = instance.get("objectid")
            if target not in constellations and target not in objects:
                raise FormatError(where, f"an instance refers to object {target!r}, which the file lacks",
                                  "the file is corrupt; export it again")
    referenced = {i.get("objectid") for c in constellations.values() for i in _children(c, "instance")}
    roots = [c for cid, c in constellations.items() if cid not in referenced]
    if not roots:
        raise FormatError(where, "every constellation is instanced by another (a cycle of instances)",
                          "the file is corrupt; export it again")

    def targets(c) -> list:
        return [i.get("objectid") for i in _children(c, "instance")]

    def inner(c) -> list:
        return [constellations[t] for t in targets(c) if t in constellations]

    def own(c) -> tuple[int, int]:
        found = [t for t in targets(c) if t not in constellations]
        return len(found), sum(len(meshes[t][1]) for t in found)

    instances, faces = instance_totals(where, roots, inner, own, "constellation")
    check_instances(where, instances, faces, "constellations")
    out: list[tuple[str, np.ndarray]] = []
    # A stack of (constellation or object id, whole transform), so that instances come out
    # in document order, a nested constellation's where it is instanced.
    stack: list = [(root, np.eye(4)) for root in reversed(roots)]
    while stack:
        target, outer = stack.pop()
        if isinstance(target, str):
            out.append((target, outer))
            continue
        pending = []
        for instance in _children(target, "instance"):
            name = instance.get("objectid")
            pending.append((constellations.get(name, name), outer @ _instance_matrix(instance, where)))
        stack.extend(reversed(pending))
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
    placed = _placements(root, objects, meshes, raw.where)
    if not any(len(meshes[oid][1]) for oid, _ in placed):
        what = (f"its {len(objects)} objects hold no <triangle> in a <mesh><volume>" if objects
                else "it holds no <object>")
        raise InputError(raw.where, what + (f" (and its constellations place {len(placed)} instances of them)"
                                            if placed and len(placed) != len(objects) else ""),
                         "export the model with its meshes")
    names = unique_names([_name(objects[oid], oid) for oid, _ in placed])
    scene = [SceneObject(name, *meshes[oid], matrix) for name, (oid, matrix) in zip(names, placed)]
    return scene_source("amf", raw.where, scene, UNITS[unit], "instances")
