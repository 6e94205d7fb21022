"""What a mesh file holds besides the positions and faces p3d reads (and writes).

p3d's writers (``p3d_cli.io.writers``) write vertex positions and triangles only. A file that
also holds colours, normals, texture coordinates, groups or materials would lose them if p3d
wrote over it; ``extras`` names them, so that a command rewriting a file in place can refuse
instead, and one writing elsewhere can say what it did not carry. (Normals of STL facets are
derived from the corners and written anew; polygons are written as the triangles they were
split into.)

Each format is looked at cheaply: a binary STL's attribute words, a PLY header, the keywords
of an OBJ's statements, an OFF's keyword and face lines.
"""

from __future__ import annotations

import os
import re

import numpy as np

#: OBJ keywords p3d's writer writes (positions, faces) or that carry nothing (comments).
_OBJ_KEPT = {b"v", b"f", b"#"}
_OBJ_NAMES = {b"vt": "texture coordinates", b"vn": "normals", b"vp": "parameter-space vertices",
              b"g": "groups", b"o": "object names", b"s": "smoothing groups", b"usemtl": "materials",
              b"mtllib": "material libraries", b"l": "lines", b"p": "points"}
_OBJ_KEY = re.compile(rb"^[ \t]*([A-Za-z_#]+)", re.M)


def extras(path: str | os.PathLike, format: str) -> list[str]:
    """What the file at ``path``, read as ``format`` (``MeshSource.format``), holds that p3d's
    writers would not write back: phrases such as ``"texture coordinates"``; empty when none."""
    try:
        if format == "stl-binary":
            return _stl(path)
        if format == "stl-ascii":
            return []               # normals (derived) and solid names only
        if format == "ply":
            return _ply(path)
        if format == "obj":
            return _obj(path)
        if format == "off":
            return _off(path)
    except (OSError, ValueError):
        return ["data p3d could not look at again"]
    return [f"everything of the {format} format but positions and faces"]


def _stl(path) -> list[str]:
    """A binary STL's attribute words (some programs keep colours there); its normals are
    derived from the corners, and written anew."""
    record = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    count = (os.path.getsize(path) - 84) // 50
    if count <= 0:
        return []
    data = np.memmap(path, dtype=record, mode="r", offset=84, shape=(count,))    # no copy of the file
    return ["per-face attribute words (colours)"] if np.any(data["attr"]) else []


def _ply(path) -> list[str]:
    from p3d_cli.io.ply.header import FACE_LISTS, parse_header
    from p3d_cli.io.raw import RawInput

    header = parse_header(RawInput(os.fspath(path), os.fspath(path), None, os.path.getsize(path)))
    out = []
    for element in header.elements:
        names = [p.name for p in element.properties]
        if element.name == "vertex":
            other = [n for n in names if n not in ("x", "y", "z")]
        elif element.name == "face":
            other = [n for n in names if n not in FACE_LISTS]
        else:
            out.append(f"the element {element.name!r}")
            continue
        if other:
            out.append(f"{element.name} properties {', '.join(other)}")
    return out


def _obj(path) -> list[str]:
    with open(path, "rb") as f:
        data = f.read()
    keys = set(_OBJ_KEY.findall(data))
    found = [_OBJ_NAMES.get(k, k.decode("ascii", "replace") + " statements") for k in sorted(keys - _OBJ_KEPT)]
    return sorted(set(found))


def _off(path) -> list[str]:
    with open(path, "rb") as f:
        head = f.read(256).lstrip()
    keyword = head.split(None, 1)[0] if head else b""
    out = []
    if keyword.startswith(b"ST"):
        out.append("texture coordinates")
    if b"C" in keyword[:4]:
        out.append("colours")
    if b"N" in keyword[:4]:
        out.append("normals")
    return out
