"""The body of an ASCII PLY file: whitespace-separated numbers, records in element order.

The grammar is ``p3d_cli.io.numbers``'s (decimal numbers, finite); records may be split over
lines (the format separates values by whitespace, not lines). Fast path: one record per line,
each element parsed with one ``np.fromstring`` (integer-only elements as int64, several times
faster than float), its lines sliced out of the body. Otherwise, or when numpy's reading could
differ from the grammar's, all numbers of the body are parsed at once as float64 and walked
element by element; a word that is not a number is reported with its line.
"""

from __future__ import annotations

from array import array

import numpy as np

from p3d_cli.errors import FormatError
from p3d_cli.io.numbers import fromstring, lone_sign, saturated, to_float
from p3d_cli.io.ply.header import HINT, Element, Header, is_kept, list_positions, wanted
from p3d_cli.warning_codes import CodedWarning

_NUMBERS_HINT = "PLY ASCII data holds only numbers; fix or export the file again"
#: Float values of integer data past this are beyond every index and count a mesh can hold.
_INDEX_LIMIT = float(1 << 53)


def read_ascii(where: str, header: Header, data: bytes):
    """``(tables, warnings)``: per kept element name, its columns (as the binary reader's)."""
    by_lines = _read_lines(where, header, data)
    if by_lines is not None:
        return by_lines
    return _read_stream(where, header, data)


def _parse(block: bytes, integers: bool) -> np.ndarray | None:
    """The numbers of ``block`` when numpy reads them as the grammar does, else None."""
    try:
        numbers = fromstring(block, np.int64 if integers else np.float64)
    except ValueError:
        return None
    if integers:
        if saturated(numbers) or lone_sign(block):
            return None
    elif not np.isfinite(numbers).all():
        return None
    return numbers


def _read_lines(where: str, header: Header, data: bytes):
    """The usual layout, one record per line; None if the layout is anything else (records
    split over lines, blank lines) or a number is in doubt: the stream parse then decides."""
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
            columns, _ = ascii_element(where, element, np.zeros(0), 0)
        else:
            end = starts[line + element.size] if line + element.size < len(starts) else len(body)
            block = body[int(starts[line]):int(end)]
            numbers = _parse(block, all(p.dtype[0] != "f" for p in element.properties))
            if numbers is None:
                return None
            try:
                columns, used = ascii_element(where, element, numbers, 0)
            except FormatError:
                return None
            if used != numbers.size:
                return None
        if is_kept(element):
            tables[element.name] = columns
        line += element.size
    rest = body[int(starts[line]):] if line < len(starts) else b""
    warnings: tuple[CodedWarning, ...] = ()
    if rest.strip():
        warnings = (CodedWarning(f"{len(rest.split())} values after the last PLY element were ignored",
                                 "trailing-data"),)
    return tables, warnings


def _read_stream(where: str, header: Header, data: bytes):
    """All numbers of the body in one parse, walked element by element (any layout)."""
    body = data[header.length:]
    numbers = _parse(body, False) if body.strip() else np.zeros(0)
    if numbers is None:
        raise FormatError(*_bad_text(where, header, data), _NUMBERS_HINT)
    pos = 0
    tables = {}
    for element in header.elements:
        columns, pos = ascii_element(where, element, numbers, pos)
        if is_kept(element):
            tables[element.name] = columns
    warnings: tuple[CodedWarning, ...] = ()
    if pos < numbers.size:
        warnings = (CodedWarning(f"{numbers.size - pos} numbers after the last PLY element were ignored",
                                 "trailing-data"),)
    return tables, warnings


def _bad_text(where: str, header: Header, data: bytes) -> tuple[str, str]:
    """Where the first word that is not a number is (only called on the error path)."""
    first_line = data[:header.length].count(b"\n") + 1
    for number, line in enumerate(data[header.length:].split(b"\n"), start=first_line):
        for word in line.split():
            try:
                to_float(word)
            except ValueError:
                return f"{where}: line {number}", f"{word.decode('utf-8', 'replace')[:40]!r} is not a number"
    return where, "unreadable ASCII data"


def ascii_element(where: str, element: Element, numbers: np.ndarray, pos: int):
    """``(columns, next position)`` of one element starting at ``numbers[pos]``."""
    total = numbers.size
    width = len(element.properties)
    if element.size * width > total - pos:  # each record holds at least one number per property
        raise FormatError(where, f"the header declares {element.size} {element.name} records but the data "
                          f"holds only {total - pos} more numbers", HINT)
    keep = wanted(element)
    if not list_positions(element) or not element.size:
        table = numbers[pos:pos + element.size * width].reshape(element.size, width)
        if element.name in ("face", "tristrips"):
            return (np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)), pos
        return [table[:, i] for i in range(width)], pos + element.size * width
    # Fast path: every record has the first record's list lengths (verified below).
    widths: list = []
    for p in element.properties:
        at = pos + sum(widths)
        if at >= total:
            raise FormatError(where, f"the data ends inside the first {element.name} record", HINT)
        widths.append(1 if p.count is None else 1 + _length(where, element, numbers[at], "the first"))
    record = sum(widths)
    starts = np.cumsum(widths) - widths
    if pos + element.size * record <= total:
        table = numbers[pos:pos + element.size * record].reshape(element.size, record)
        if all((table[:, starts[i]] == widths[i] - 1).all() for i in list_positions(element)):
            return _columns(where, element, table, starts, keep), pos + element.size * record
    return _walk(where, element, numbers, pos, keep)


def _length(where: str, element: Element, value, which: str) -> int:
    """A list length read as a number: a non-negative integer (the numbers are finite)."""
    value = float(value)
    if value < 0 or value != int(value):
        raise FormatError(where, f"bad list length {value!r} in {which} {element.name} record", HINT)
    return int(value)


def _columns(where, element, table, starts, keep):
    if element.name in ("face", "tristrips"):
        for i, p in enumerate(element.properties):
            if p.name in keep:
                k = int(table[0, starts[i]]) if len(table) else 0
                items = table[:, starts[i] + 1:starts[i] + 1 + k]
                return integral(where, items.reshape(-1)), np.full(len(table), k, dtype=np.int64)
    return [table[:, starts[i]] if p.count is None else None for i, p in enumerate(element.properties)]


class _Window:
    """``numbers[i]`` as Python floats, converted a window at a time: item access on a list is
    several times faster than on an array, and a window bounds the memory the list takes."""

    SIZE = 1 << 16

    def __init__(self, numbers: np.ndarray) -> None:
        self.numbers, self.start = numbers, 0
        self.values: list = []

    def __getitem__(self, i: int) -> float:
        if not self.start <= i < self.start + len(self.values):
            self.start, self.values = i, self.numbers[i:i + self.SIZE].tolist()
        return self.values[i - self.start]


def _walk(where, element, numbers, pos, keep):
    """Record by record, for lists of varying length. Kept lists are recorded as (start, size)
    in compact arrays and gathered in one pass at the end."""
    total = numbers.size
    values = _Window(numbers)
    scalars = {i: array("d") for i, p in enumerate(element.properties) if p.count is None}
    starts, sizes = array("q"), array("q")
    for _ in range(element.size):
        for i, p in enumerate(element.properties):
            if pos >= total:
                raise FormatError(where, f"the data ends inside the {element.name} records "
                                  f"(the header declares {element.size})", HINT)
            if p.count is None:
                scalars[i].append(values[pos])
                pos += 1
                continue
            n = _length(where, element, values[pos], "a")
            if pos + 1 + n > total:
                raise FormatError(where, f"the data ends inside the {element.name} records "
                                  f"(the header declares {element.size})", HINT)
            if p.name in keep:
                starts.append(pos + 1)
                sizes.append(n)
            pos += 1 + n
    if element.name in ("face", "tristrips"):
        first = np.frombuffer(starts, dtype=np.int64)
        counts = np.frombuffer(sizes, dtype=np.int64)
        index = np.repeat(first - (np.cumsum(counts) - counts), counts) + np.arange(int(counts.sum()))
        return (integral(where, numbers[index]), counts.copy()), pos
    return [np.frombuffer(scalars[i], dtype=np.float64).copy() if i in scalars else None
            for i in range(len(element.properties))], pos


def integral(where: str, values: np.ndarray) -> np.ndarray:
    """Face indices as int64: integers stay, whole floats are converted, others are refused."""
    if values.dtype.kind in "iu":
        return values.astype(np.int64, copy=False)
    whole = np.floor(values)
    wrong = (whole != values) | (np.abs(values) > _INDEX_LIMIT)
    if wrong.any():
        bad = float(values[np.flatnonzero(wrong)[0]])
        what = "is not an integer" if bad != int(bad) else "is out of range for a vertex index"
        raise FormatError(where, f"face vertex index {bad!r} {what}", HINT)
    return values.astype(np.int64)
