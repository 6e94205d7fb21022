"""Object File Format (OFF, with its COFF/NOFF/STOFF variants).

``OFF`` (the counts ``nv nf [ne]`` may follow on the same line), then ``nv`` vertex lines
(``x y z`` plus normals, colours or texture coordinates in the variants) and ``nf`` face lines
``k i1 .. ik`` (0-based, optionally followed by a colour). ``#`` starts a comment and blank
lines are allowed anywhere. Polygons are split as fans from their first vertex; coordinates are
parsed as float64.

One record per line is what every writer does and what this reader requires, so each line's
extra values can be told from the next record's. The lines are parsed all at once: a sentinel
after every line marks where each line's numbers end.
"""

from __future__ import annotations

import re

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.numbers import fromstring, lone_sign, saturated, to_float, to_int
from p3d_cli.io.polygons import fan_triangles
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source
from p3d_cli.warning_codes import CodedWarning

_KEYWORD = re.compile(rb"^(ST)?C?N?(4)?(n)?OFF$")
_COMMENT = re.compile(rb"#[^\n]*")
_HINT = "fix the file or export it again"


def load(raw: RawInput) -> MeshSource:
    """Read an OFF file.

    Raises
    ------
    FormatError
        Bad header, counts claiming more lines than the file holds, malformed lines, or a face
        index out of range (with the line number).
    InputError
        No faces.
    """
    data = raw.read_all()
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    if b"#" in data:
        data = _COMMENT.sub(b"", data)  # keeps the newlines, so line numbers stay right
    numbered = [(n, line) for n, line in enumerate(data.split(b"\n"), start=1) if line.strip()]
    if not numbered:
        raise FormatError(raw.where, "the file holds no OFF data", _HINT)
    nv, nf, body = _header(raw.where, numbered)
    if nf == 0:
        raise InputError(raw.where, f"no faces (the OFF header declares {nv} vertices and 0 faces)",
                         "export the mesh with its faces, not as a point cloud")
    if len(body) < nv + nf:
        raise FormatError(raw.where, f"the header declares {nv} vertices and {nf} faces ({nv + nf} lines) but "
                          f"only {len(body)} lines follow", "the file is truncated; export it again")
    vertices = _vertices(raw.where, body[:nv])
    faces = _faces(raw.where, body[nv:nv + nf], nv)
    warnings: tuple[CodedWarning, ...] = ()
    if len(body) > nv + nf:
        warnings = (CodedWarning(f"{len(body) - nv - nf} lines after the last face were ignored", "skipped-lines"),)
    return indexed_source("off", vertices, faces, "float64", warnings)


def _header(where: str, numbered: list[tuple[int, bytes]]):
    number, line = numbered[0]
    words = line.split()
    match = _KEYWORD.match(words[0])
    if not match:
        raise FormatError(f"{where}: line {number}", f"expected an 'OFF' header, found {words[0][:20]!r}",
                          "the file is not an OFF file")
    if match.group(2) or match.group(3):
        raise FormatError(f"{where}: line {number}", f"{words[0].decode()} (4-D or n-D vertices) is not supported",
                          "convert the mesh to 3-D OFF, OBJ or PLY")
    rest = numbered[1:]
    counts = words[1:]
    if not counts:
        if not rest:
            raise FormatError(where, "the file ends after the 'OFF' line", "the file is truncated")
        number, line = rest[0]
        counts = line.split()
        rest = rest[1:]
    try:
        if len(counts) not in (2, 3):
            raise ValueError
        values = [to_int(c) for c in counts]
        if min(values) < 0:
            raise ValueError
    except ValueError:
        text = b" ".join(counts).decode("utf-8", "replace")[:60]
        raise FormatError(f"{where}: line {number}", f"expected the counts 'vertices faces edges', found {text!r}",
                          _HINT) from None
    return values[0], values[1], rest


def _per_line(lines: list[bytes], integers: bool):
    """All numbers of ``lines`` and each line's count and start, or None if numpy's reading
    could differ from the grammar's (a word that is no number, ``nan``, a lone sign, ...)."""
    marker = b" -1 " if integers else b" nan "
    text = (marker + b"\n").join(lines) + marker
    try:
        numbers = fromstring(text, np.int64 if integers else np.float64)
    except ValueError:
        return None
    if integers:
        if saturated(numbers) or lone_sign(text):
            return None
        ends = np.flatnonzero(numbers == -1)
    else:
        ends = np.flatnonzero(np.isnan(numbers))
        if np.isinf(numbers).any():
            return None
    if ends.size != len(lines):
        return None  # a -1 (or a NaN) among the numbers: the caller reads them another way
    counts = np.diff(ends, prepend=-1) - 1
    return numbers, counts, ends - counts


def _bad_line(where: str, numbered, what: str):
    """The first of ``numbered`` lines holding a word that is no number, as a FormatError."""
    for number, line in numbered:
        for word in line.split():
            try:
                to_float(word)
            except ValueError:
                text = line.decode("utf-8", "replace").strip()[:60]
                return FormatError(f"{where}: line {number}", f"expected {what}, found {text!r} "
                                   f"({word.decode('utf-8', 'replace')[:20]!r} is not a finite decimal number)",
                                   _HINT)
    return FormatError(where, f"malformed {what} lines", _HINT)


def _vertices(where: str, numbered) -> np.ndarray:
    if not numbered:
        return np.zeros((0, 3))
    parsed = _per_line([line for _, line in numbered], False)
    if parsed is None:
        raise _bad_line(where, numbered, "a vertex 'x y z'")
    numbers, counts, starts = parsed
    short = np.flatnonzero(counts < 3)
    if short.size:
        number, line = numbered[int(short[0])]
        raise FormatError(f"{where}: line {number}", f"expected a vertex 'x y z', found "
                          f"{line.decode('utf-8', 'replace').strip()[:60]!r}", _HINT)
    return numbers[starts[:, None] + np.arange(3)]


def _faces(where: str, numbered, vertex_count: int) -> np.ndarray:
    lines = [line for _, line in numbered]
    parsed = _per_line(lines, True)
    if parsed is None:
        # Colours after the indices may be floats (or a -1 is among the numbers): parse as float.
        parsed = _per_line(lines, False)
        if parsed is None:
            raise _bad_line(where, numbered, "a face 'k i1 .. ik'")
    numbers, counts, starts = parsed
    sizes = numbers[starts]
    bad = np.flatnonzero((counts < 1) | (sizes < 3) | (sizes > counts - 1) | (sizes != np.floor(sizes)))
    if bad.size:
        number, line = numbered[int(bad[0])]
        raise FormatError(f"{where}: line {number}", "expected a face 'k i1 .. ik' with k >= 3, found "
                          f"{line.decode('utf-8', 'replace').strip()[:60]!r}", _HINT)
    sizes = sizes.astype(np.int64)
    owner = np.repeat(np.arange(len(sizes)), sizes)
    offset = np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    corners = numbers[starts[owner] + 1 + offset]
    wrong = (corners < 0) | (corners >= vertex_count) | (corners != np.floor(corners))
    if wrong.any():
        first = int(np.flatnonzero(wrong)[0])
        number, line = numbered[int(owner[first])]
        # The index as written (numbers may have been rounded to float64 on the way).
        shown = line.split()[1 + int(offset[first])].decode("ascii", "replace")
        raise FormatError(f"{where}: line {number}", f"face index {shown} is out of range: the file has "
                          f"{vertex_count} vertices (indices 0 to {vertex_count - 1})",
                          "fix the face or export the mesh again")
    return fan_triangles(corners.astype(np.int64), sizes)
