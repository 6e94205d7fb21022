"""The PLY header: elements in file order, each with a count and properties.

A property is a scalar of one of eight types (two spellings each) or a list (a count, then that
many items). p3d needs ``vertex`` (``x``, ``y``, ``z``) and either ``face`` (list
``vertex_indices`` or ``vertex_index``) or ``tristrips`` (the same list, strips separated by
``-1``); every other element and property is read past and ignored.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.raw import RawInput

#: PLY type names (both spellings) -> numpy type codes, without byte order.
TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
#: Bytes per value of each type code (Python integers: sizes are computed before numpy sees them).
ITEMSIZE = {"i1": 1, "u1": 1, "i2": 2, "u2": 2, "i4": 4, "u4": 4, "f4": 4, "f8": 8}
FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
FACE_LISTS = ("vertex_indices", "vertex_index")
#: Elements whose index list p3d reads (the polygons, or the strips).
POLYGON_ELEMENTS = ("face", "tristrips")
_MAX_HEADER = 1 << 20
_END_HEADER = re.compile(rb"\nend_header[ \t]*(?:\r?\n|$)")
HINT = "the file is truncated or corrupt; export it again"


@dataclass(frozen=True)
class Property:
    """One property: ``dtype`` is the scalar's (or the list items') type, ``count`` the list
    length's type, or None for a scalar."""

    name: str
    dtype: str
    count: str | None = None


@dataclass(frozen=True)
class Element:
    """One element: its name, record count and properties in record order."""

    name: str
    size: int
    properties: tuple[Property, ...]
    line: int = 0  # header line number, for messages


@dataclass(frozen=True)
class Header:
    """The parsed header: ``format`` (``ascii``, ``binary_*``), the elements, and ``length``,
    the bytes up to and including the ``end_header`` line."""

    format: str
    elements: tuple[Element, ...]
    length: int


def parse_header(raw: RawInput) -> Header:
    """Read and check the header.

    Raises
    ------
    FormatError
        Not a PLY file, no ``end_header``, unknown format or type, malformed lines, or two
        elements of a name p3d reads (``vertex``, ``face``, ``tristrips``).
    """
    head = raw.head(_MAX_HEADER)
    # The end_header line, not the words in a comment (binary data follows its newline).
    found = _END_HEADER.search(head)
    end = found.start() + 1 if found else -1
    if not head.startswith(b"ply") or end == -1:
        what = "not a PLY file (no 'ply' first line)" if not head.startswith(b"ply") else \
            f"no 'end_header' line in the first {len(head)} bytes"
        raise FormatError(raw.where, what, HINT)
    newline = head.find(b"\n", end)
    if newline == -1:
        newline = len(head)
    if head[end:newline].strip() != b"end_header":
        raise FormatError(raw.where, "malformed 'end_header' line", HINT)
    # Keywords are ASCII; a comment in another encoding should not make the file unreadable.
    lines = head[:end].decode("ascii", "replace").replace("\r", "").split("\n")
    if lines[0].strip() != "ply":
        raise FormatError(f"{raw.where}: header line 1", "the first line must be 'ply'", HINT)
    fmt, elements = _header_lines(raw.where, lines)
    return Header(fmt, tuple(elements), newline + 1)


def _header_lines(where: str, lines: list[str]) -> tuple[str, list[Element]]:
    """The format and the elements declared by the header lines after ``ply``."""
    fmt = None
    elements: list[Element] = []
    props: list[Property] = []
    for number, line in enumerate(lines[1:], start=2):
        words = line.split()
        at = f"{where}: header line {number}"
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            fmt = _format(at, words, line)
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit() or not words[2].isascii():
                raise FormatError(at, f"expected 'element NAME COUNT', found {line.strip()!r}", HINT)
            _close(elements, props)
            if words[1] in ("vertex",) + POLYGON_ELEMENTS and any(e.name == words[1] for e in elements):
                raise FormatError(at, f"a second '{words[1]}' element (the header already declares one)",
                                  "a mesh has one vertex and one face element; export it again")
            props = []
            elements.append(Element(words[1], int(words[2]), (), number))
        elif words[0] == "property":
            if not elements:
                raise FormatError(at, "a property before any element", HINT)
            props.append(_property(at, words))
        else:
            raise FormatError(at, f"unexpected header line {line.strip()!r}", HINT)
    _close(elements, props)
    if fmt is None:
        raise FormatError(where, "the PLY header has no 'format' line", HINT)
    return fmt, elements


def _close(elements: list[Element], props: list[Property]) -> None:
    """Give the last element the properties read since its line."""
    if elements:
        last = elements.pop()
        elements.append(Element(last.name, last.size, tuple(props), last.line))


def _format(where: str, words: list[str], line: str) -> str:
    if len(words) != 3 or words[1] not in FORMATS:
        raise FormatError(where, f"unknown format line {line.strip()!r}",
                          "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'")
    if words[2] != "1.0":
        raise FormatError(where, f"unsupported PLY version {words[2]!r}", "only version 1.0 exists")
    return words[1]


def _property(where: str, words: list[str]) -> Property:
    if len(words) == 5 and words[1] == "list":
        for name in words[2:4]:
            if name not in TYPES:
                raise FormatError(where, f"unknown property type {name!r}", "PLY types are " + ", ".join(TYPES))
        if TYPES[words[2]][0] == "f":
            raise FormatError(where, f"a list length of type {words[2]!r}", "list lengths must be integers")
        return Property(words[4], TYPES[words[3]], TYPES[words[2]])
    if len(words) == 3:
        if words[1] not in TYPES:
            raise FormatError(where, f"unknown property type {words[1]!r}", "PLY types are " + ", ".join(TYPES))
        return Property(words[2], TYPES[words[1]])
    raise FormatError(where, f"expected 'property TYPE NAME' or 'property list COUNT ITEM NAME', "
                      f"found {' '.join(words)!r}", HINT)


def required_elements(where: str, header: Header) -> tuple[Element, list[Element]]:
    """The vertex element and the polygon elements (``face`` and/or ``tristrips``) p3d reads.

    Raises
    ------
    FormatError
        No vertex element, no x/y/z, no index list, or indices stored as floats.
    InputError
        No faces (no polygon element, or only empty ones).
    """
    by_name = {e.name: e for e in header.elements}
    vertex = by_name.get("vertex")
    if vertex is None:
        raise FormatError(where, "the PLY header declares no 'vertex' element", "export the mesh again")
    scalars = {p.name for p in vertex.properties if p.count is None}
    missing = [axis for axis in "xyz" if axis not in scalars]
    if missing:
        raise FormatError(where, f"the vertex element has no {'/'.join(missing)} property",
                          "export the mesh with vertex positions")
    polygons = [by_name[name] for name in POLYGON_ELEMENTS if name in by_name]
    if not any(e.size for e in polygons):
        raise InputError(where, "no faces (the face element is empty)" if polygons else
                         "no faces (the PLY file holds no face element)",
                         "export the mesh with its faces, not as a point cloud")
    for element in polygons:
        lists = [p for p in element.properties if p.name in FACE_LISTS and p.count is not None]
        if not lists:
            raise FormatError(where, f"the {element.name} element has no 'vertex_indices' list",
                              "export the mesh again")
        if lists[0].dtype[0] == "f":
            raise FormatError(where, f"{element.name} vertex indices are stored as floats", "export the mesh again")
    return vertex, polygons


def wanted(element: Element) -> set[str]:
    """Properties kept per element: x, y, z of vertices; the index list of faces and strips."""
    if element.name == "vertex":
        return {"x", "y", "z"}
    if element.name in POLYGON_ELEMENTS:
        names = [p.name for p in element.properties if p.count is not None and p.name in FACE_LISTS]
        return {names[0]} if names else set()
    return set()


def list_positions(element: Element) -> list[int]:
    """Indices of the element's list properties."""
    return [i for i, p in enumerate(element.properties) if p.count is not None]


def is_kept(element: Element) -> bool:
    """True for the elements whose values p3d uses."""
    return element.name == "vertex" or element.name in POLYGON_ELEMENTS
