"""PLY (Stanford polygon file), ASCII and binary of either byte order.

The header (``p3d_cli.io.ply.header``) lists elements in file order; p3d reads ``vertex``
(``x``, ``y``, ``z``) and ``face`` (polygons, split as fans from their first vertex) and/or
``tristrips`` (triangle strips separated by ``-1``); every other element and property (colours,
normals, the texture list of trimesh's fuze.ply, ...) is read past and ignored. Binary
``float`` coordinates are float32 (widened later, never here).

The bodies are read by ``p3d_cli.io.ply.binary`` and ``p3d_cli.io.ply.ascii``. A header never
makes p3d allocate what it claims: every count is checked against the bytes (binary) or numbers
(ASCII) actually present first.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.ply.ascii import read_ascii
from p3d_cli.io.ply.binary import read_binary
from p3d_cli.io.ply.header import TYPES, Element, Header, Property, parse_header, required_elements
from p3d_cli.io.polygons import fan_triangles, strip_triangles
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source

__all__ = ["TYPES", "Element", "Header", "Property", "load", "parse_header"]


def load(raw: RawInput) -> MeshSource:
    """Read a PLY file.

    Raises
    ------
    FormatError
        Bad header, unknown property type, missing x/y/z or face list, truncated data, a
        header claiming more than the file holds, or a face index out of range.
    InputError
        No faces.
    """
    header = parse_header(raw)
    vertex, polygons = required_elements(raw.where, header)
    data = raw.read_all()
    if header.format == "ascii":
        tables, warnings = read_ascii(raw.where, header, data)
    else:
        tables, warnings = read_binary(raw.where, header, data)
    vertices, single = _vertices(header, vertex, tables["vertex"])
    pieces = []
    for element in polygons:
        corners, sizes = tables[element.name]
        if element.name == "face":
            pieces.append(_faces(raw.where, corners, sizes, len(vertices)))
        else:
            pieces.append(_strips(raw.where, corners, sizes, len(vertices)))
    faces = pieces[0] if len(pieces) == 1 else np.concatenate(pieces)
    return indexed_source("ply", vertices, faces, "float32" if single else "float64", warnings)


def _vertices(header: Header, vertex: Element, columns) -> tuple[np.ndarray, bool]:
    """The ``(n, 3)`` positions, and whether they are kept as float32 (binary ``float``)."""
    names = [p.name for p in vertex.properties]
    picked = [columns[names.index(axis)] for axis in "xyz"]
    types = {vertex.properties[names.index(axis)].dtype for axis in "xyz"}
    single = header.format != "ascii" and "f4" in types
    if single and types == {"f4"}:
        return np.stack(picked, axis=1).astype(np.float32, copy=False), True
    return np.stack([np.asarray(c, dtype=np.float64) for c in picked], axis=1), single


def _check_range(where: str, corners: np.ndarray, vertex_count: int, name: str, sizes=None) -> None:
    if corners.size and (corners.min() < 0 or corners.max() >= vertex_count):
        corners = corners.reshape(-1)   # (a binary file's triangles come as (n, 3) rows)
        bad = int(np.flatnonzero((corners < 0) | (corners >= vertex_count))[0])
        item = int(np.searchsorted(np.cumsum(sizes), bad, side="right")) if sizes is not None else None
        which = f"face {item}" if item is not None else f"a {name} index list"
        raise FormatError(where, f"{which} refers to vertex {int(corners[bad])}, but the file has "
                          f"{vertex_count} vertices (indices 0 to {vertex_count - 1})",
                          "the file is corrupt; export the mesh again")


def _faces(where: str, corners: np.ndarray, sizes: np.ndarray, vertex_count: int) -> np.ndarray:
    """Check the polygons and split them into ``(n, 3)`` int64 triangles."""
    small = np.flatnonzero(sizes < 3)
    if small.size:
        raise FormatError(where, f"face {int(small[0])} has {int(sizes[small[0]])} vertices (at least 3 needed)",
                          "remove degenerate faces or export the mesh again")
    # Indices of 32 bits or fewer, signed, stay int32 (a binary PLY's usual ``int``): half the
    # memory and time of widening every corner to int64; the triangles are the same.
    kind, size = corners.dtype.kind, corners.dtype.itemsize
    narrow = kind in "iu" and (size < 4 or (size == 4 and kind == "i"))
    corners = corners.astype(np.int32 if narrow else np.int64, copy=False)
    _check_range(where, corners, vertex_count, "face", sizes)
    return fan_triangles(corners, sizes)


def _strips(where: str, indices: np.ndarray, sizes: np.ndarray, vertex_count: int) -> np.ndarray:
    """Triangles of a ``tristrips`` element (records of strips; -1 ends a strip)."""
    indices = indices.astype(np.int64, copy=False)
    # A record's list ends its last strip too: a -1 between records keeps their strips apart.
    indices = np.insert(indices, np.cumsum(sizes)[:-1], -1)
    _check_range(where, indices[indices != -1], vertex_count, "tristrips")
    return strip_triangles(indices)
