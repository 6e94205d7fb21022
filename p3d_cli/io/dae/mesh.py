"""One COLLADA ``<geometry>``: its positions and all its triangles, whatever its materials.

A ``<mesh>`` holds ``<source>`` arrays, a ``<vertices>`` element naming the POSITION source,
and primitives that index it (COLLADA 1.4.1 specification, chapter 5 "Geometry"):

- ``<triangles>``, ``<polylist>`` (with ``<vcount>``), ``<polygons>`` (one ``<p>`` per polygon),
  ``<tristrips>`` and ``<trifans>`` (one ``<p>`` per strip or fan) make triangles; polygons and
  fans are split from their first vertex, strips alternate their winding (``p3d_cli.io.polygons``);
- ``<lines>`` and ``<linestrips>`` hold no volume: they are counted and left out;
- every primitive's ``<p>`` interleaves one index per input: the stride is the largest input
  ``offset`` plus one, and the VERTEX input's offset picks the position index;
- an ``<accessor>`` reads its array from ``offset``, ``stride`` values per element, and its
  ``<param>`` elements name the values it yields (a param without a name is skipped): the
  positions are the values named X, Y and Z, else the first three named.

All primitives of a geometry are one mesh: its material groups (the ``material`` attribute,
bound or not by ``<bind_material>``) play no part in what is measured. Positions are read as
float64, the decimal text rounded once.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.numbers import lone_sign, saturated, to_float, to_int
from p3d_cli.io.polygons import fan_triangles

_HINT = "the file is corrupt; export it again"
#: Primitives that make triangles, and those that hold no volume.
SOLID_PRIMITIVES = ("triangles", "polylist", "polygons", "tristrips", "trifans")
LINE_PRIMITIVES = ("lines", "linestrips")


def local(tag) -> str:
    """An element's tag without its namespace."""
    return tag.rsplit("}", 1)[-1] if isinstance(tag, str) else ""


def children(node, name: str) -> list:
    return [child for child in node if local(child.tag) == name]


def child(node, name: str):
    for found in node:
        if local(found.tag) == name:
            return found
    return None


@dataclass(frozen=True)
class GeometryMesh:
    """A geometry's positions and triangles.

    Attributes
    ----------
    vertices : (m, 3) float64
        In the unit of the geometry's scope (``unit_element`` says whose).
    faces : (n, 3) int64
    lines : int
        Line primitives left out.
    unit_element : Element
        The element whose scope sets the positions' unit (their ``<source>``).
    """

    vertices: np.ndarray
    faces: np.ndarray
    lines: int
    unit_element: object


def floats(text: str | None, where: str, what: str) -> np.ndarray:
    """Whitespace-separated decimal numbers as float64 (``nan`` and ``inf`` are read as such,
    and refused later with the face that uses them).

    Raises
    ------
    FormatError
    """
    words = (text or "").split()
    try:
        return np.array(words, dtype=np.float64)
    except ValueError:
        pass
    for word in words:
        try:
            to_float(word.encode())
        except ValueError:
            if word.lower().lstrip("+-") not in ("nan", "inf", "infinity"):
                raise FormatError(where, f"{what} holds {word[:40]!r}, which is not a number", _HINT) from None
    return np.array([float(w) for w in words], dtype=np.float64)


def indices(text: str | None, where: str, what: str) -> np.ndarray:
    """Whitespace-separated non-negative integers as int64 (numpy's fast parse, checked; the
    careful parse names the first bad word).

    Raises
    ------
    FormatError
    """
    data = (text or "").encode("ascii", "replace")
    if not data.strip():
        return np.zeros(0, dtype=np.int64)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            values = np.fromstring(data, dtype=np.int64, sep=" ")
            if not lone_sign(data) and not saturated(values) and (not values.size or values.min() >= 0):
                return values
        except (ValueError, DeprecationWarning):
            pass
    out = []
    for word in data.split():
        try:
            value = to_int(word)
        except ValueError:
            raise FormatError(where, f"{what} holds {word[:40].decode(errors='replace')!r}, which is not an index",
                              _HINT) from None
        if not 0 <= value < 1 << 62:
            raise FormatError(where, f"{what} holds the index {word[:40].decode(errors='replace')}, outside "
                              "0..2^62", _HINT)
        out.append(value)
    return np.array(out, dtype=np.int64)


def positions(source, document, where: str) -> np.ndarray:
    """The ``(m, 3)`` positions a ``<source>`` yields through its accessor."""
    common = child(source, "technique_common")
    accessor = child(common, "accessor") if common is not None else None
    if accessor is None:
        raise FormatError(where, f"source {source.get('id')!r} has no <technique_common><accessor>", _HINT)
    array = document.resolve(accessor.get("source"), where, "accessor source")
    if array is None:
        array = child(source, "float_array")
    if array is None or local(array.tag) != "float_array":
        raise FormatError(where, f"the positions of source {source.get('id')!r} are not a <float_array>", _HINT)
    values = floats(array.text, where, f"float_array {array.get('id')!r}")
    params = children(accessor, "param")
    named = [i for i, p in enumerate(params) if p.get("name")]
    by_name = {(params[i].get("name") or "").upper(): i for i in named}
    picks = [by_name[k] for k in "XYZ"] if all(k in by_name for k in "XYZ") else named[:3]
    try:
        count = int(accessor.get("count", "-1"))
        stride = int(accessor.get("stride", str(max(len(params), 1))))
        offset = int(accessor.get("offset", "0"))
    except ValueError:
        raise FormatError(where, f"accessor of {source.get('id')!r}: count, stride and offset must be integers",
                          _HINT) from None
    if len(picks) < 3 or count < 0 or offset < 0 or stride < len(params) or stride < 1:
        raise FormatError(where, f"accessor of {source.get('id')!r} does not yield X, Y, Z positions (count "
                          f"{count}, stride {stride}, offset {offset}, {len(named)} named params)", _HINT)
    if count == 0:  # no element: the stride and offset index nothing (a huge stride overflows int64)
        return np.zeros((0, 3))
    needed = offset + (count - 1) * stride + max(picks) + 1
    if needed > len(values):
        raise FormatError(where, f"accessor of {source.get('id')!r} reads {count} elements of {stride} values from "
                          f"offset {offset}, but its array holds {len(values)} values", _HINT)
    # With one element the stride steps nowhere (and may be past int64); with more, the check
    # above bounds it by the array's length.
    step = 0 if count == 1 else stride
    return values[offset + np.arange(count)[:, None] * step + np.array(picks)]


def geometry_mesh(geometry, document, where: str) -> GeometryMesh:
    """The positions and triangles of one ``<geometry>`` (see the module's description).

    Raises
    ------
    FormatError
        Not a mesh (``<spline>``, ``<brep>``, a hull of another geometry), polygons with holes, a
        missing source, an index outside the positions.
    """
    name = geometry.get("id") or geometry.get("name") or "(unnamed)"
    at = f"{where}: geometry {name!r}"
    mesh = child(geometry, "mesh")
    if mesh is None:
        mesh = child(geometry, "convex_mesh")
    if mesh is None:
        kinds = [local(c.tag) for c in geometry if local(c.tag) not in ("asset", "extra")]
        raise FormatError(at, f"is a <{kinds[0] if kinds else 'nothing'}>, not a <mesh>: p3d measures triangle meshes",
                          "export the model as a triangle mesh")
    if mesh.get("convex_hull_of"):
        raise FormatError(at, f"is the convex hull of {mesh.get('convex_hull_of')!r} (<convex_mesh "
                          "convex_hull_of>), which p3d does not compute", "export the hull as a mesh")
    vertices_element = child(mesh, "vertices")
    source = _position_source(vertices_element, document, at) if vertices_element is not None else None
    points = positions(source, document, at) if source is not None else np.zeros((0, 3))
    pieces, lines = [], 0
    for primitive in mesh:
        kind = local(primitive.tag)
        if kind in LINE_PRIMITIVES:
            lines += 1
        elif kind in SOLID_PRIMITIVES:
            if source is None:
                raise FormatError(at, "has primitives but no <vertices> with a POSITION input", _HINT)
            pieces.append(_primitive_faces(primitive, kind, vertices_element, document, at))
    faces = np.concatenate(pieces) if pieces else np.zeros((0, 3), dtype=np.int64)
    if len(faces) and faces.max() >= len(points):
        raise FormatError(at, f"a primitive refers to position {int(faces.max())}, but the mesh has "
                          f"{len(points)}", _HINT)
    return GeometryMesh(points, faces, lines, source)


def _position_source(vertices_element, document, where: str):
    for entry in children(vertices_element, "input"):
        if entry.get("semantic") == "POSITION":
            found = document.resolve(entry.get("source"), where, "POSITION source")
            if found is None or local(found.tag) != "source":
                raise FormatError(where, f"the POSITION input names {entry.get('source')!r}, which is no <source>",
                                  _HINT)
            return found
    raise FormatError(where, "its <vertices> has no POSITION input", _HINT)


def _primitive_faces(primitive, kind: str, vertices_element, document, where: str) -> np.ndarray:
    """The triangles (position indices) of one primitive element."""
    at = f"{where}: <{kind}>"
    stride, offset = _layout(primitive, vertices_element, document, at)
    if kind == "polygons" and children(primitive, "ph"):
        raise FormatError(at, "holds polygons with holes (<ph>), which p3d does not triangulate",
                          "export the model with triangles")
    if kind in ("triangles", "polylist"):
        corners = _corners(child(primitive, "p"), stride, offset, at)
        if kind == "triangles":
            if len(corners) % 3:
                raise FormatError(at, f"holds {len(corners)} vertices, not a whole number of triangles", _HINT)
            return corners.reshape(-1, 3)
        sizes = indices(getattr(child(primitive, "vcount"), "text", ""), at, "<vcount>")
        if len(sizes) and sizes.max() > len(corners) or int(sizes.sum(dtype=object)) != len(corners):
            raise FormatError(at, f"<vcount> adds up to {int(sizes.sum(dtype=object))} vertices, but <p> holds "
                              f"{len(corners)}", _HINT)
        return _polygons(corners, sizes)
    lists = [_corners(p, stride, offset, at) for p in children(primitive, "p")]
    if kind == "polygons":
        return _polygons(np.concatenate(lists) if lists else np.zeros(0, dtype=np.int64),
                         np.array([len(c) for c in lists], dtype=np.int64))
    out = [(_strip if kind == "tristrips" else _fan)(corners) for corners in lists if len(corners) >= 3]
    return np.concatenate(out) if out else np.zeros((0, 3), dtype=np.int64)


def _layout(primitive, vertices_element, document, where: str) -> tuple[int, int]:
    """The index stride of a primitive's ``<p>`` and the offset of its VERTEX input."""
    offsets, vertex = [], None
    for entry in children(primitive, "input"):
        try:
            value = int(entry.get("offset", "0"))
        except ValueError:
            raise FormatError(where, f"an input offset is {entry.get('offset')!r}, not an integer", _HINT) from None
        if not 0 <= value < 1 << 16:
            raise FormatError(where, f"an input offset is {value}, outside 0..65535", _HINT)
        offsets.append(value)
        if entry.get("semantic") == "VERTEX":
            if document.resolve(entry.get("source"), where, "VERTEX source") is not vertices_element:
                raise FormatError(where, f"its VERTEX input names {entry.get('source')!r}, not the mesh's <vertices>",
                                  _HINT)
            vertex = value
    if vertex is None:
        raise FormatError(where, "has no VERTEX input", _HINT)
    return max(offsets) + 1, vertex


def _corners(p, stride: int, offset: int, where: str) -> np.ndarray:
    values = indices(p.text if p is not None else "", where, "<p>")
    if len(values) % stride:
        raise FormatError(where, f"<p> holds {len(values)} indices, not a multiple of its {stride} inputs", _HINT)
    return values[offset::stride]


def _polygons(corners: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    keep = sizes >= 3
    if keep.all():
        return fan_triangles(corners, sizes)
    # Polygons of fewer than 3 vertices enclose nothing: drop their corners.
    owner = np.repeat(keep, sizes)
    return fan_triangles(corners[owner], sizes[keep])


def _strip(corners: np.ndarray) -> np.ndarray:
    """Triangles ``(c[i], c[i+1], c[i+2])``, every second one reversed to keep the winding."""
    tri = np.stack([corners[:-2], corners[1:-1], corners[2:]], axis=1)
    tri[1::2, :2] = tri[1::2, 1::-1]
    return tri


def _fan(corners: np.ndarray) -> np.ndarray:
    return fan_triangles(corners, np.array([len(corners)]))
