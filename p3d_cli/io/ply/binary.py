"""The body of a binary PLY file (either byte order).

Fast path: an element whose lists all have the first record's lengths is one
``np.frombuffer`` with a structured dtype (the lengths are then verified, never assumed).
Other elements take a record-by-record walk. Every size and offset is computed with Python
integers and checked against the bytes present *before* numpy sees it: a header or a list
length can then never make numpy allocate what the file does not hold, overflow a dtype's
itemsize (a list of 2^30 ushorts once made the record size negative and crashed the process)
or read past the buffer.
"""

from __future__ import annotations

import struct
from array import array

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.ply.header import FORMATS, HINT, ITEMSIZE, Element, Header, is_kept, list_positions, wanted
from p3d_cli.warning_codes import CodedWarning


def read_binary(where: str, header: Header, data: bytes):
    """``(tables, warnings)``: per kept element name, its columns (see ``_columns``)."""
    order = FORMATS[header.format]
    offset = header.length
    tables = {}
    for element in header.elements:
        remaining = len(data) - offset
        fixed = sum(ITEMSIZE[p.count or p.dtype] for p in element.properties)
        if element.size * fixed > remaining:
            # Checked before anything is allocated: a lying header costs nothing.
            raise FormatError(where, f"the header declares {element.size} {element.name} records "
                              f"(at least {element.size * fixed} bytes) but only {remaining} bytes remain",
                              HINT)
        columns, offset = _element(where, element, data, offset, order)
        if is_kept(element):
            tables[element.name] = columns
    warnings: tuple[CodedWarning, ...] = ()
    if offset < len(data):
        warnings = (CodedWarning(f"{len(data) - offset} trailing bytes after the PLY data were ignored",
                                 "trailing-data"),)
    return tables, warnings


def _element(where: str, element: Element, data: bytes, offset: int, order: str):
    keep = wanted(element)
    if element.size == 0:
        return _empty(element, keep), offset
    lengths = _first_lengths(where, element, data, offset, order)
    record_size = sum(ITEMSIZE[p.dtype] for p in element.properties if p.count is None)
    record_size += sum(ITEMSIZE[p.count] + n * ITEMSIZE[p.dtype]
                       for p, n in zip([p for p in element.properties if p.count is not None], lengths))
    need = element.size * record_size
    if need <= len(data) - offset:
        fields: list[tuple] = []
        it = iter(lengths)
        for i, p in enumerate(element.properties):
            if p.count is None:
                fields.append((f"p{i}", order + p.dtype))
            else:
                fields.append((f"n{i}", order + p.count))
                fields.append((f"p{i}", order + p.dtype, (next(it),)))
        table = np.frombuffer(data, np.dtype(fields), element.size, offset)
        if all((table[f"n{i}"] == n).all() for i, n in zip(list_positions(element), lengths)):
            return _columns(element, table, keep), offset + need
    # Lists of varying length (or a first record whose layout does not fit): walk the records.
    return _walk(where, element, data, offset, order, keep)


def _empty(element: Element, keep: set):
    if element.name in ("face", "tristrips"):
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)
    return [np.zeros(0) if p.name in keep else None for p in element.properties]


def _first_lengths(where: str, element: Element, data: bytes, offset: int, order: str) -> list[int]:
    """The list lengths of the first record, each checked to fit in the bytes left."""
    lengths = []
    for p in element.properties:
        if p.count is None:
            offset += ITEMSIZE[p.dtype]
            continue
        size = ITEMSIZE[p.count]
        if offset + size > len(data):
            raise FormatError(where, f"the file ends inside the first {element.name} record", HINT)
        n = int(np.frombuffer(data, order + p.count, 1, offset)[0])
        if n < 0:
            raise FormatError(where, f"negative list length {n} in the first {element.name} record", HINT)
        offset += size + n * ITEMSIZE[p.dtype]
        if offset > len(data):
            raise FormatError(where, f"the first {element.name} record's list holds {n} items, more than the "
                              f"{len(data) - offset + n * ITEMSIZE[p.dtype]} bytes left", HINT)
        lengths.append(n)
    return lengths


def _columns(element: Element, table: np.ndarray, keep: set):
    """For a polygon element ``(corners, sizes)``; for others one array per property, None for
    properties not kept."""
    if element.name in ("face", "tristrips"):
        for i, p in enumerate(element.properties):
            if p.name in keep:
                items = np.asarray(table[f"p{i}"]).reshape(len(table), -1)
                k = items.shape[1]
                if element.name == "face" and k == 3:
                    # Triangles: their (n, 3) indices where they lie in the file's records (a
                    # count byte and three indices each), not copied; the kernels read them
                    # with these strides. The sizes are one number seen n times.
                    return items, np.broadcast_to(np.int64(3), (len(table),))
                return items.reshape(-1), np.full(len(table), k, dtype=np.int64)
    return [table[f"p{i}"] if p.name in keep else None for i, p in enumerate(element.properties)]


def _walk(where: str, element: Element, data: bytes, offset: int, order: str, keep: set):
    """Record by record, for lists of varying length (mixed triangles and quads, ...)."""
    steps: list[tuple] = []
    for p in element.properties:
        if p.count is None:
            steps.append((None, struct.Struct(order + np.dtype(p.dtype).char), p.name in keep))
        else:
            steps.append((struct.Struct(order + np.dtype(p.count).char), ITEMSIZE[p.dtype], p.name in keep))
    # Compact arrays, not lists: 8 bytes per value, a small multiple of the file at most.
    scalars = {p.name: array("d") for p in element.properties if p.count is None and p.name in keep}
    starts, sizes = array("q"), array("q")
    end = len(data)
    view = memoryview(data)
    try:
        for _ in range(element.size):
            for (count, kind, kept), p in zip(steps, element.properties):
                if count is None:
                    value = kind.unpack_from(view, offset)[0]
                    offset += kind.size
                    if kept:
                        scalars[p.name].append(value)
                    continue
                n = count.unpack_from(view, offset)[0]
                offset += count.size
                stop = offset + n * kind
                if n < 0 or stop > end:
                    raise struct.error
                if kept:
                    starts.append(offset)
                    sizes.append(n)
                offset = stop
    except struct.error:
        raise FormatError(where, f"the file ends inside the {element.name} records "
                          f"(the header declares {element.size})", HINT) from None
    if element.name in ("face", "tristrips"):
        item = next(np.dtype(order + p.dtype) for p in element.properties if p.count is not None and p.name in keep)
        sizes_array = np.frombuffer(sizes, dtype=np.int64).copy()
        return (_gather(data, np.frombuffer(starts, dtype=np.int64), sizes_array, item), sizes_array), offset
    return [np.frombuffer(scalars[p.name], dtype=np.float64).copy() if p.name in scalars else None
            for p in element.properties], offset


def _gather(data: bytes, starts: np.ndarray, sizes: np.ndarray, item: np.dtype) -> np.ndarray:
    """The lists at byte offsets ``starts`` (``sizes`` items each), concatenated, in one gather.

    The walk has checked that every list lies inside ``data``. Lists need not be aligned to the
    item size, so the file is viewed as items once per possible misalignment (at most 8 views,
    no copies) and each list is gathered from the view that matches its start: one int64 index
    per item, not per byte.
    """
    size = item.itemsize
    out = np.empty(int(sizes.sum()), dtype=item)
    ends = np.cumsum(sizes)
    for shift in range(size):
        chosen = np.flatnonzero(starts % size == shift)
        if not chosen.size:
            continue
        view = np.frombuffer(data, item, (len(data) - shift) // size, shift)
        n = sizes[chosen]
        within = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        source = np.repeat((starts[chosen] - shift) // size, n) + within
        target = np.repeat(ends[chosen] - n, n) + within
        out[target] = view[source]
    return out
