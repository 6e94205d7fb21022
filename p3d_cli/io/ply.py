"""PLY (Stanford polygon file), ASCII and binary of either byte order.

The header lists elements in file order, each with a count and properties; a property is a
scalar of one of eight types (two spellings each) or a list (a count, then that many items).
p3d needs ``vertex`` (``x``, ``y``, ``z``) and ``face`` (list ``vertex_indices`` or
``vertex_index``); every other element and property (colours, normals, the texture list of
trimesh's fuze.ply, ...) is read past and ignored. Polygons are split as fans from their first
vertex. Binary ``float`` coordinates are float32 (FACTS.md: widened later, never here).

Fast paths: a binary element whose lists all have the first record's lengths is one
``np.frombuffer`` with a structured dtype (the lengths are then verified, never assumed), and
ASCII data is one ``np.fromstring`` of the whole body, sliced per element. Other files take a
record-by-record walk. A header never makes p3d allocate what it claims: every count is
checked against the bytes (binary) or numbers (ASCII) actually present first.
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.obj import fan_triangles
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source

#: PLY type names (both spellings) -> numpy type codes, without byte order.
TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_FACE_LISTS = ("vertex_indices", "vertex_index")
_MAX_HEADER = 1 << 20
_END_HEADER = re.compile(rb"\nend_header[ \t]*(?:\r?\n|$)")
_HINT = "the file is truncated or corrupt; export it again"


@dataclass(frozen=True)
class Property:
    """One property: ``dtype`` is the scalar's (or the list items') type, ``count`` the list
    length's type, or None for a scalar."""

    name: str
    dtype: str
    count: str | None = None


@dataclass(frozen=True)
class Element:
    name: str
    size: int
    properties: tuple[Property, ...]


@dataclass(frozen=True)
class Header:
    format: str
    elements: tuple[Element, ...]
    length: int  # bytes up to and including the end_header line


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
    vertex, face = _required_elements(raw.where, header)
    data = raw.read_all()
    if header.format == "ascii":
        tables, warnings = _read_ascii(raw.where, header, data)
    else:
        tables, warnings = _read_binary(raw.where, header, data)
    names = [p.name for p in vertex.properties]
    columns = [tables["vertex"][names.index(axis)] for axis in "xyz"]
    types = {vertex.properties[names.index(axis)].dtype for axis in "xyz"}
    single = header.format != "ascii" and "f4" in types
    if single and types == {"f4"}:
        vertices = np.stack(columns, axis=1).astype(np.float32, copy=False)
    else:
        vertices = np.stack([np.asarray(c, dtype=np.float64) for c in columns], axis=1)
    corners, sizes = tables["face"]
    faces = _faces(raw.where, corners, sizes, len(vertices))
    return indexed_source("ply", vertices, faces, "float32" if single else "float64", warnings)


# --- header ------------------------------------------------------------------------------

def parse_header(raw: RawInput) -> Header:
    """Read and check the header.

    Raises
    ------
    FormatError
        Not a PLY file, no ``end_header``, unknown format or type, malformed lines.
    """
    head = raw.head(_MAX_HEADER)
    # The end_header line, not the words in a comment (binary data follows its newline).
    found = _END_HEADER.search(head)
    end = found.start() + 1 if found else -1
    if not head.startswith(b"ply") or end == -1:
        what = "not a PLY file (no 'ply' first line)" if not head.startswith(b"ply") else \
            f"no 'end_header' line in the first {len(head)} bytes"
        raise FormatError(raw.where, what, _HINT)
    newline = head.find(b"\n", end)
    if newline == -1:
        newline = len(head)
    # Keywords are ASCII; a comment in another encoding should not make the file unreadable.
    text = head[:end].decode("ascii", "replace")
    if head[end:newline].strip() != b"end_header":
        raise FormatError(raw.where, "malformed 'end_header' line", _HINT)
    lines = text.replace("\r", "").split("\n")
    if lines[0].strip() != "ply":
        raise FormatError(f"{raw.where}: header line 1", "the first line must be 'ply'", _HINT)
    fmt = None
    elements: list[Element] = []
    props: list[Property] = []

    def close_element():
        if elements:
            last = elements.pop()
            elements.append(Element(last.name, last.size, tuple(props)))

    for number, line in enumerate(lines[1:], start=2):
        words = line.split()
        where = f"{raw.where}: header line {number}"
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            if len(words) != 3 or words[1] not in _FORMATS:
                raise FormatError(where, f"unknown format line {line.strip()!r}",
                                  "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'")
            if words[2] != "1.0":
                raise FormatError(where, f"unsupported PLY version {words[2]!r}", "only version 1.0 exists")
            fmt = words[1]
        elif words[0] == "element":
            if len(words) != 3 or not words[2].isdigit():
                raise FormatError(where, f"expected 'element NAME COUNT', found {line.strip()!r}", _HINT)
            close_element()
            props = []
            elements.append(Element(words[1], int(words[2]), ()))
        elif words[0] == "property":
            if not elements:
                raise FormatError(where, "a property before any element", _HINT)
            props.append(_property(where, words))
        else:
            raise FormatError(where, f"unexpected header line {line.strip()!r}", _HINT)
    close_element()
    if fmt is None:
        raise FormatError(raw.where, "the PLY header has no 'format' line", _HINT)
    return Header(fmt, tuple(elements), newline + 1)


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
                      f"found {' '.join(words)!r}", _HINT)


def _required_elements(where: str, header: Header) -> tuple[Element, Element]:
    by_name = {e.name: e for e in header.elements}
    vertex = by_name.get("vertex")
    if vertex is None:
        raise FormatError(where, "the PLY header declares no 'vertex' element", "export the mesh again")
    scalars = {p.name for p in vertex.properties if p.count is None}
    missing = [axis for axis in "xyz" if axis not in scalars]
    if missing:
        raise FormatError(where, f"the vertex element has no {'/'.join(missing)} property",
                          "export the mesh with vertex positions")
    face = by_name.get("face")
    if face is None or face.size == 0:
        raise InputError(where, "no faces (the PLY file holds no face element)" if face is None else
                         "no faces (the face element is empty)", "export the mesh with its faces, not as a point cloud")
    lists = [p for p in face.properties if p.name in _FACE_LISTS and p.count is not None]
    if not lists:
        raise FormatError(where, "the face element has no 'vertex_indices' list", "export the mesh again")
    if lists[0].dtype[0] == "f":
        raise FormatError(where, "face vertex indices are stored as floats", "export the mesh again")
    return vertex, face


def _wanted(element: Element):
    """Properties kept per element: x, y, z of vertices; the index list of faces."""
    if element.name == "vertex":
        return {"x", "y", "z"}
    if element.name == "face":
        names = [p.name for p in element.properties if p.count is not None and p.name in _FACE_LISTS]
        return {names[0]} if names else set()
    return set()


# --- binary ------------------------------------------------------------------------------

def _read_binary(where: str, header: Header, data: bytes):
    order = _FORMATS[header.format]
    offset = header.length
    tables = {}
    for element in header.elements:
        remaining = len(data) - offset
        fixed = sum(np.dtype(p.count or p.dtype).itemsize for p in element.properties)
        if element.size * fixed > remaining:
            # Checked before anything is allocated: a lying header costs nothing.
            raise FormatError(where, f"the header declares {element.size} {element.name} records "
                              f"(at least {element.size * fixed} bytes) but only {remaining} bytes remain",
                              _HINT)
        result = _binary_element(where, element, data, offset, order)
        columns, offset = result
        if element.name in ("vertex", "face") and element.name not in tables:
            tables[element.name] = columns
    warnings = ()
    if offset < len(data):
        warnings = (f"{len(data) - offset} trailing bytes after the PLY data were ignored",)
    return tables, warnings


def _binary_element(where: str, element: Element, data: bytes, offset: int, order: str):
    wanted = _wanted(element)
    lengths = _first_lengths(where, element, data, offset, order) if element.size else []
    fields, it = [], iter(lengths)
    for i, p in enumerate(element.properties):
        if p.count is None:
            fields.append((f"p{i}", order + p.dtype))
        else:
            fields.append((f"n{i}", order + p.count))
            fields.append((f"p{i}", order + p.dtype, (next(it),)))
    record = np.dtype(fields)
    need = element.size * record.itemsize
    if need <= len(data) - offset:
        table = np.frombuffer(data, record, element.size, offset)
        same = all((table[f"n{i}"] == n).all() for (i, n) in zip(_list_positions(element), lengths))
        if same:
            return _columns(element, table, wanted), offset + need
    # Lists of varying length (or a first record that does not fit): walk record by record.
    return _walk_binary(where, element, data, offset, order, wanted)


def _list_positions(element: Element) -> list[int]:
    return [i for i, p in enumerate(element.properties) if p.count is not None]


def _first_lengths(where, element, data, offset, order) -> list[int]:
    lengths = []
    for p in element.properties:
        if p.count is None:
            offset += np.dtype(p.dtype).itemsize
            continue
        size = np.dtype(p.count).itemsize
        if offset + size > len(data):
            raise FormatError(where, f"the file ends inside the first {element.name} record", _HINT)
        n = int(np.frombuffer(data, order + p.count, 1, offset)[0])
        if n < 0:
            raise FormatError(where, f"negative list length {n} in the first {element.name} record", _HINT)
        lengths.append(n)
        offset += size + n * np.dtype(p.dtype).itemsize
    return lengths


def _columns(element: Element, table: np.ndarray, wanted: set):
    """For the face element ``(corners, sizes)``; for others one array per property, None for
    properties not wanted."""
    if element.name == "face":
        for i, p in enumerate(element.properties):
            if p.name in wanted:
                items = np.asarray(table[f"p{i}"]).reshape(len(table), -1)
                k = items.shape[1]
                return items.reshape(-1), np.full(len(table), k, dtype=np.int64)
    return [table[f"p{i}"] if p.name in wanted else None for i, p in enumerate(element.properties)]


def _walk_binary(where, element, data, offset, order, wanted):
    """Record by record, for lists of varying length (mixed triangles and quads, ...)."""
    steps = []
    for p in element.properties:
        if p.count is None:
            steps.append((None, struct.Struct(order + np.dtype(p.dtype).char), p.name in wanted))
        else:
            steps.append((struct.Struct(order + np.dtype(p.count).char), np.dtype(order + p.dtype),
                          p.name in wanted))
    scalars = {p.name: [] for p in element.properties if p.count is None and p.name in wanted}
    starts, sizes = [], []
    end = len(data)
    view = memoryview(data)
    try:
        for _ in range(element.size):
            for (count, kind, keep), p in zip(steps, element.properties):
                if count is None:
                    value = kind.unpack_from(view, offset)[0]
                    offset += kind.size
                    if keep:
                        scalars[p.name].append(value)
                else:
                    n = count.unpack_from(view, offset)[0]
                    offset += count.size
                    stop = offset + n * kind.itemsize
                    if n < 0 or stop > end:
                        raise struct.error
                    if keep:
                        starts.append(offset)
                        sizes.append(n)
                    offset = stop
    except struct.error:
        raise FormatError(where, f"the file ends inside the {element.name} records "
                          f"(the header declares {element.size})", _HINT) from None
    if element.name == "face":
        item = next(kind for (count, kind, keep) in steps if count is not None and keep)
        return (_gather(data, np.array(starts, dtype=np.int64), np.array(sizes, dtype=np.int64), item),
                np.array(sizes, dtype=np.int64)), offset
    return [np.array(scalars[p.name]) if p.name in scalars else None for p in element.properties], offset


def _gather(data: bytes, starts: np.ndarray, sizes: np.ndarray, item: np.dtype) -> np.ndarray:
    """The lists at byte offsets ``starts`` (``sizes`` items each), concatenated, in one gather."""
    width = sizes * item.itemsize
    total = int(width.sum())
    within = np.arange(total) - np.repeat(np.cumsum(width) - width, width)
    index = np.repeat(starts, width) + within
    return np.frombuffer(data, np.uint8)[index].view(item)


# --- ASCII -------------------------------------------------------------------------------

def _read_ascii(where: str, header: Header, data: bytes):
    by_lines = _read_ascii_lines(where, header, data)
    if by_lines is not None:
        return by_lines
    return _read_ascii_stream(where, header, data)


def _read_ascii_lines(where: str, header: Header, data: bytes):
    """The usual layout, one record per line: each element's lines are parsed on their own,
    integer-only elements as int64 (several times faster than float). None if the layout is
    anything else (records split over lines, blank lines); the stream parse then decides."""
    body = data[header.length:]
    if b"\r" in body:
        body = body.replace(b"\r", b" ")
    breaks = np.flatnonzero(np.frombuffer(body, dtype=np.uint8) == 10)
    total = sum(e.size for e in header.elements)
    if len(breaks) < total - 1 or b"\n\n" in body:
        return None
    starts = np.concatenate(([0], breaks + 1))
    tables, line = {}, 0
    for element in header.elements:
        if not element.size:
            columns, _ = _ascii_element(where, element, np.zeros(0), 0)
        else:
            end = starts[line + element.size] if line + element.size < len(starts) else len(body)
            block = body[int(starts[line]):int(end)]
            integers = all(p.dtype[0] != "f" for p in element.properties)
            try:
                numbers = np.fromstring(block, dtype=np.int64 if integers else np.float64, sep=" ")
            except ValueError:
                return None
            try:
                columns, used = _ascii_element(where, element, numbers, 0)
            except FormatError:
                return None
            if used != numbers.size:
                return None
        if element.name in ("vertex", "face") and element.name not in tables:
            tables[element.name] = columns
        line += element.size
    rest = body[int(starts[line]):] if line < len(starts) else b""
    warnings = ()
    if rest.strip():
        warnings = (f"{len(rest.split())} values after the last PLY element were ignored",)
    return tables, warnings


def _read_ascii_stream(where: str, header: Header, data: bytes):
    """All numbers of the body in one parse, walked element by element (any layout)."""
    body = data[header.length:]
    try:
        numbers = np.fromstring(body, dtype=np.float64, sep=" ") if body.strip() else np.zeros(0)
    except ValueError:
        raise FormatError(*_bad_text(where, header, data), "PLY ASCII data holds only numbers; fix or "
                          "export the file again") from None
    pos = 0
    tables = {}
    for element in header.elements:
        columns, pos = _ascii_element(where, element, numbers, pos)
        if element.name in ("vertex", "face") and element.name not in tables:
            tables[element.name] = columns
    warnings = ()
    if pos < numbers.size:
        warnings = (f"{numbers.size - pos} numbers after the last PLY element were ignored",)
    return tables, warnings


def _bad_text(where: str, header: Header, data: bytes):
    """Where the first non-number in the ASCII data is (only called on the error path)."""
    first_line = data[:header.length].count(b"\n") + 1
    for number, line in enumerate(data[header.length:].split(b"\n"), start=first_line):
        for word in line.split():
            try:
                float(word)
            except ValueError:
                return f"{where}: line {number}", f"{word.decode('utf-8', 'replace')[:40]!r} is not a number"
    return where, "unreadable ASCII data"


def _ascii_element(where: str, element: Element, numbers: np.ndarray, pos: int):
    total = numbers.size
    lists = _list_positions(element)
    width = len(element.properties)
    if element.size * width > total - pos:  # each record holds at least one number per property
        raise FormatError(where, f"the header declares {element.size} {element.name} records but the data "
                          f"holds only {total - pos} more numbers", _HINT)
    wanted = _wanted(element)
    if not lists:
        table = numbers[pos:pos + element.size * width].reshape(element.size, width)
        return [table[:, i] for i in range(width)], pos + element.size * width
    # Fast path: every record has the first record's list lengths (verified below).
    lengths, widths, at = [], [], pos
    for p in element.properties:
        if at >= total:
            raise FormatError(where, f"the data ends inside the first {element.name} record", _HINT)
        if p.count is None:
            widths.append(1)
            at += 1
        else:
            n = numbers[at]
            if n < 0 or n != int(n):
                raise FormatError(where, f"bad list length {n!r} in the first {element.name} record", _HINT)
            lengths.append(int(n))
            widths.append(1 + int(n))
            at += 1 + int(n)
    record = sum(widths)
    starts = np.cumsum(widths) - widths
    if element.size and pos + element.size * record <= total:
        table = numbers[pos:pos + element.size * record].reshape(element.size, record)
        if all((table[:, starts[i]] == n).all() for i, n in zip(lists, lengths)):
            return _ascii_columns(where, element, table, starts, wanted), pos + element.size * record
    return _walk_ascii(where, element, numbers, pos, wanted)


def _ascii_columns(where, element, table, starts, wanted):
    if element.name == "face":
        for i, p in enumerate(element.properties):
            if p.name in wanted:
                k = int(table[0, starts[i]]) if len(table) else 0
                items = table[:, starts[i] + 1:starts[i] + 1 + k]
                return _integral(where, items.reshape(-1)), np.full(len(table), k, dtype=np.int64)
    return [table[:, starts[i]] if p.count is None else None for i, p in enumerate(element.properties)]


def _walk_ascii(where, element, numbers, pos, wanted):
    """Record by record, for lists of varying length."""
    total = numbers.size
    values = numbers.tolist() if element.name == "face" else None
    scalars = {i: [] for i, p in enumerate(element.properties) if p.count is None}
    pieces, sizes = [], []
    for _ in range(element.size):
        for i, p in enumerate(element.properties):
            if pos >= total:
                raise FormatError(where, f"the data ends inside the {element.name} records "
                                  f"(the header declares {element.size})", _HINT)
            if p.count is None:
                scalars[i].append(numbers[pos])
                pos += 1
                continue
            n = values[pos] if values is not None else float(numbers[pos])
            if n < 0 or n != int(n):
                raise FormatError(where, f"bad list length {n!r} in a {element.name} record", _HINT)
            n = int(n)
            if pos + 1 + n > total:
                raise FormatError(where, f"the data ends inside the {element.name} records "
                                  f"(the header declares {element.size})", _HINT)
            if p.name in wanted:
                pieces.append((pos + 1, n))
                sizes.append(n)
            pos += 1 + n
    if element.name == "face":
        index = np.concatenate([np.arange(a, a + n) for a, n in pieces]) if pieces else np.zeros(0, dtype=np.int64)
        return (_integral(where, numbers[index]), np.array(sizes, dtype=np.int64)), pos
    return [np.array(scalars[i]) if i in scalars else None for i in range(len(element.properties))], pos


def _integral(where: str, values: np.ndarray) -> np.ndarray:
    if values.dtype.kind in "iu":
        return values.astype(np.int64, copy=False)
    whole = np.floor(values)
    if not (whole == values).all():
        bad = values[np.flatnonzero(whole != values)[0]]
        raise FormatError(where, f"face vertex index {bad!r} is not an integer", _HINT)
    return values.astype(np.int64)


# --- faces -------------------------------------------------------------------------------

def _faces(where: str, corners: np.ndarray, sizes: np.ndarray, vertex_count: int) -> np.ndarray:
    """Check the polygons and split them into ``(n, 3)`` int64 triangles."""
    small = np.flatnonzero(sizes < 3)
    if small.size:
        raise FormatError(where, f"face {int(small[0])} has {int(sizes[small[0]])} vertices (at least 3 needed)",
                          "remove degenerate faces or export the mesh again")
    corners = corners.astype(np.int64, copy=False)
    if corners.size and (corners.min() < 0 or corners.max() >= vertex_count):
        bad = int(np.flatnonzero((corners < 0) | (corners >= vertex_count))[0])
        face = int(np.searchsorted(np.cumsum(sizes), bad, side="right"))
        raise FormatError(where, f"face {face} refers to vertex {int(corners[bad])}, but the file has "
                          f"{vertex_count} vertices (indices 0 to {vertex_count - 1})",
                          "the file is corrupt; export the mesh again")
    return fan_triangles(corners, sizes)
