"""Wavefront OBJ: ``v`` vertices and ``f`` faces; everything else is ignored.

Faces are polygons of any size, split as a fan from their first vertex (``v0, vi, vi+1``,
the convention of the reference values). A face corner is ``a``, ``a/b``, ``a//c`` or
``a/b/c``, and in the three-field form the trailing fields may be empty (``a/b/``, ``a//``);
only ``a`` matters.
Indices are 1-based, or negative: ``-1`` is the last vertex defined *before that face line*.
Coordinates are decimal numbers (``p3d_cli.io.numbers``), parsed as float64 (the decimal text
rounded once), and nothing is merged or repaired.

Statements with other keywords (``vt``, ``usemtl``, free-form ``cstype`` ...) are skipped, the
unknown ones with a warning. A line that is no statement at all (a bare ``1/617/894`` is seen
in real models) is skipped with a warning naming the first such line, as long as such lines are
at most half of the statements: a file made mostly of them is not an OBJ file and is refused,
at its first such line.

Two parsers, one grammar: ``p3d_cli.io.obj.fast`` reads what exporters write at C speed, a
chunk of lines at a time, and answers None for a chunk holding anything else; the careful
line-by-line parser here then reads that chunk, and names the line of any error.
"""

from __future__ import annotations

from array import array
from collections import Counter

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.numbers import to_float, to_int
from p3d_cli.io.obj.fast import CONTINUATION, IGNORED, chunks_of, parse_chunk
from p3d_cli.io.polygons import fan_triangles
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source
from p3d_cli.warning_codes import CodedWarning

_IGNORED = frozenset(IGNORED)
_HINT = "fix the file or export it again"
#: Lines that are no statement are skipped as long as they are at most half of all lines that
#: hold something (a real model's stray ``1/617/894`` lines); a file made mostly of them is
#: not an OBJ, and is refused at its first one rather than read as a handful of faces.
_GARBLED_RATIO = 2
#: Indices beyond this cannot address any mesh (and would not fit the int64 arrays).
_INDEX_LIMIT = 1 << 62


def looks_like_obj(head: bytes) -> bool:
    """True when the first statement of ``head`` is an OBJ keyword (for inputs with no extension)."""
    if b"\0" in head:
        return False
    for line in head.splitlines():
        words = line.split()
        if not words or words[0].startswith(b"#"):
            continue
        return words[0] in _IGNORED or words[0] in (b"v", b"f")
    return False


def load(raw: RawInput) -> MeshSource:
    """Read an OBJ file.

    Returns
    -------
    MeshSource
        ``format="obj"``, float64 vertices, polygons split into fans.

    Raises
    ------
    FormatError
        A malformed statement, or a face index out of range (with the line number and index).
    InputError
        No faces.
    """
    with raw.open() as stream:
        read = read_chunks(raw.where, chunks_of(stream))
    if read is None:
        with raw.open() as stream:
            vertices, faces, warnings = parse_lines(raw.where, chunks_of(stream))
    else:
        vertices, faces, warnings, _ = read
    source = indexed_source("obj", vertices, faces, "float64", warnings)
    if source.face_count == 0:
        raise InputError(raw.where, f"no faces (the file defines {len(vertices)} vertices and no 'f' lines)",
                         "export the mesh with its faces, not as a point cloud")
    return source


def read_chunks(where: str, chunks):
    """The file chunk by chunk: each by the fast path (``fast.parse_chunk``), or, when it
    holds anything else (an unknown statement, a stray line, an error), by the careful parser,
    with the file's line numbers. So a real model with a few odd lines is read at the fast
    path's speed but for the chunks that hold them.

    Returns
    -------
    (vertices, faces, warnings, careful) or None
        ``faces``: the chunks' ``(k, 3)`` index arrays, not joined (``indexed_source`` reads
        them as one: the largest array an OBJ holds is never held twice); ``careful``: the
        number of chunks the careful parser read. None when the file must be read by the
        careful parser as a whole: ``\\`` continuation lines (which may span two chunks), or a
        face index out of range (whose message needs the face's line).

    Raises
    ------
    FormatError
        A malformed statement (the first in the file), or a file made mostly of stray lines.
    """
    skipped = _Skipped()
    vertex_blocks, face_blocks = [], []
    defined = lines = careful = 0
    for chunk in chunks:
        if b"\\" in chunk and CONTINUATION.search(chunk):
            return None
        fast = None if b"\0" in chunk else parse_chunk(chunk, defined)
        if fast is None:
            careful += 1
            vertices, triangles = _careful_chunk(where, chunk, lines, defined, skipped)
        else:
            vertices, triangles, statements = fast
            skipped.statements += statements
        lines += chunk.count(b"\n") + (not chunk.endswith(b"\n"))
        defined += len(vertices)
        vertex_blocks.append(vertices)
        if len(triangles):
            face_blocks.append(triangles)
        del fast, vertices, triangles
    _refuse_garbled(where, skipped)
    vertices = np.concatenate(vertex_blocks) if vertex_blocks else np.zeros((0, 3))
    del vertex_blocks
    for block in face_blocks:
        if block.min() < 0 or block.max() >= len(vertices):
            return None
    return vertices, face_blocks, _warnings(skipped), careful


def _parse_fast(data: bytes):
    """The fast path on one text (CR line ends allowed): ``(vertices, faces)``, the faces joined
    into one ``(n, 3)`` int64 array as the careful parser gives them, or None unless every
    chunk took the fast path."""
    try:
        read = read_chunks("<text>", chunks_of(_Bytes(data)))
    except FormatError:  # found by the careful parser, in a chunk the fast path did not take
        return None
    if read is None or read[3]:
        return None
    vertices, blocks = read[0], read[1]
    return vertices, (np.concatenate(blocks) if blocks else np.zeros((0, 3))).astype(np.int64)


def _parse_lines(where: str, data: bytes):
    """The careful parser on one text: ``(vertices, faces, warnings)``."""
    return parse_lines(where, chunks_of(_Bytes(data)))


class _Bytes:
    """A ``read``-able view of bytes held in memory."""

    def __init__(self, data: bytes) -> None:
        self.data, self.pos = memoryview(data), 0

    def read(self, n: int) -> bytes:
        piece = bytes(self.data[self.pos:self.pos + n])
        self.pos += len(piece)
        return piece


# --- careful path ------------------------------------------------------------------------

def _lines(where: str, chunks, number: int = 0):
    """``(line number, line)`` over chunks of whole lines, numbered after ``number``.

    Raises
    ------
    FormatError
        A NUL byte: binary data, not text.
    """
    for chunk in chunks:
        lines = chunk.split(b"\n")
        if b"\0" in chunk:
            bad = next(i for i, line in enumerate(lines) if b"\0" in line)
            raise FormatError(f"{where}: line {number + bad + 1}", "binary data (a NUL byte) in an OBJ file",
                              "the file is corrupt or not an OBJ")
        if chunk.endswith(b"\n"):
            lines.pop()
        for line in lines:
            number += 1
            yield number, line


def _statements(where: str, chunks, before: int = 0):
    """``(line number, words)`` per statement, joining ``\\`` continuations, dropping comments;
    lines numbered after the ``before`` lines of earlier chunks."""
    pending: list[bytes] = []
    start = 0
    for number, line in _lines(where, chunks, before):
        if b"#" in line:
            line = line[:line.index(b"#")]
        if line.rstrip().endswith(b"\\"):
            if not pending:
                start = number
            pending.append(line.rstrip()[:-1])
            continue
        if pending:
            pending.append(line)
            line = b" ".join(pending)
            pending = []
            number = start
        words = line.split()
        if words:
            yield number, words
    if pending:
        words = b" ".join(pending).split()
        if words:
            yield start, words


def _text(words: list[bytes]) -> str:
    return b" ".join(words).decode("utf-8", "replace")[:60]


class _Skipped:
    """The statements a file holds and those skipped, over all its chunks."""

    def __init__(self) -> None:
        self.statements = 0
        self.unknown: Counter = Counter()
        self.first_unknown = 0
        self.garbled = 0
        self.first_garbled: tuple[int, list[bytes]] | None = None


class _Mesh:
    """What the careful parser collects, in compact arrays (8 bytes per number)."""

    def __init__(self, skipped: _Skipped, base: int = 0) -> None:
        self.vertices = array("d")
        self.corners = array("q")
        self.sizes = array("q")
        self.face_line = array("q")
        self.skipped = skipped
        self.base = base            # vertices defined before (in earlier chunks)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(vertices (v, 3) float64, corners, sizes)``: the vertices copied out of the buffer,
        the other two views of it."""
        vertices = np.frombuffer(self.vertices, dtype=np.float64).reshape(-1, 3).copy()
        return vertices, np.frombuffer(self.corners, dtype=np.int64), np.frombuffer(self.sizes, dtype=np.int64)


def parse_lines(where: str, chunks):
    """Line by line, with line numbers in every error. Returns vertices, faces, warnings."""
    skipped = _Skipped()
    mesh = _Mesh(skipped)
    for number, words in _statements(where, chunks):
        _statement(where, number, words, mesh)
    _refuse_garbled(where, skipped)
    vertices, corners, sizes = mesh.arrays()
    _check_range(where, corners, sizes, mesh.face_line, len(vertices))
    return vertices, fan_triangles(corners, sizes), _warnings(skipped)


def _careful_chunk(where: str, chunk: bytes, lines: int, defined: int, skipped: _Skipped):
    """``(vertices, triangles)`` of one chunk by the careful parser: its lines numbered after
    the ``lines`` before it, its relative indices counted from the ``defined`` vertices before
    it (indices are checked against the vertex count by the caller, at the end)."""
    mesh = _Mesh(skipped, defined)
    for number, words in _statements(where, [chunk], lines):
        _statement(where, number, words, mesh)
    vertices, corners, sizes = mesh.arrays()
    return vertices, fan_triangles(corners, sizes)


def _statement(where: str, number: int, words: list[bytes], mesh: _Mesh) -> None:
    skipped = mesh.skipped
    skipped.statements += 1
    key = words[0]
    if key == b"v":
        _vertex(where, number, words, mesh)
    elif key == b"f":
        _face(where, number, words, mesh)
    elif key in _IGNORED:
        return
    elif key[:1].isalpha():
        skipped.unknown[key.decode("utf-8", "replace")] += 1
        skipped.first_unknown = skipped.first_unknown or number
    else:
        skipped.garbled += 1
        skipped.first_garbled = skipped.first_garbled or (number, words)


def _refuse_garbled(where: str, skipped: _Skipped) -> None:
    """A file made mostly of lines that are no statement is not an OBJ: refused at the first."""
    if skipped.garbled and skipped.garbled * _GARBLED_RATIO > skipped.statements:
        assert skipped.first_garbled is not None
        number, words = skipped.first_garbled
        raise FormatError(f"{where}: line {number}", f"unexpected {_text(words)!r} in an OBJ file",
                          "the file is corrupt or not an OBJ")


def _vertex(where: str, number: int, words: list[bytes], mesh: _Mesh) -> None:
    try:
        if len(words) not in (4, 5, 7):
            raise ValueError
        values = [to_float(w) for w in words[1:]]
    except ValueError:
        raise FormatError(f"{where}: line {number}", f"expected 'v X Y Z [W]' with finite decimal numbers, "
                          f"found {_text(words)!r}", _HINT) from None
    mesh.vertices.extend(values[:3])


def _face(where: str, number: int, words: list[bytes], mesh: _Mesh) -> None:
    if len(words) < 4:
        raise FormatError(f"{where}: line {number}",
                          f"a face needs at least 3 vertices, found {_text(words)!r}", _HINT)
    defined = mesh.base + len(mesh.vertices) // 3
    for word in words[1:]:
        index = _corner(where, number, word)
        if index < 0:
            resolved = defined + index
            if resolved < 0:
                raise FormatError(f"{where}: line {number}",
                                  f"relative face index {index} reaches before the first vertex "
                                  f"(only {defined} defined before this line)", _HINT)
            mesh.corners.append(resolved)
        else:
            mesh.corners.append(index - 1)
    mesh.sizes.append(len(words) - 1)
    mesh.face_line.append(number)


def _corner(where: str, number: int, word: bytes) -> int:
    """The vertex index of one corner ``a``, ``a/b``, ``a//c``, ``a/b/c`` (the last two fields of
    the three-field form may be empty: ``a/b/``, ``a//``; ``a/`` is not a corner), checked to be a
    non-zero integer that can address a vertex."""
    parts = word.split(b"/")
    try:
        if len(parts) > 3 or (len(parts) == 2 and not parts[1]) or any(p and to_int(p) == 0 for p in parts[1:]):
            raise ValueError
        index = to_int(parts[0])
    except ValueError:
        raise FormatError(f"{where}: line {number}",
                          f"bad face corner {word.decode('utf-8', 'replace')[:40]!r} (expected a, a/b, "
                          "a//c or a/b/c with non-zero integers)", _HINT) from None
    if index == 0:
        raise FormatError(f"{where}: line {number}", "face index 0 (OBJ indices start at 1)", _HINT)
    if abs(index) > _INDEX_LIMIT:
        raise FormatError(f"{where}: line {number}", f"face index {index} is out of range", _HINT)
    return index


def _check_range(where: str, corners: np.ndarray, sizes: np.ndarray, face_line, vertex_count: int) -> None:
    if not corners.size:
        return
    bad = np.flatnonzero(corners >= vertex_count)
    if bad.size:
        face = int(np.searchsorted(np.cumsum(sizes), bad[0], side="right"))
        raise FormatError(f"{where}: line {face_line[face]}",
                          f"face index {int(corners[bad[0]]) + 1} is out of range: the file defines "
                          f"{vertex_count} vertices", "fix the face or export the mesh again")


def _warnings(skipped: _Skipped) -> tuple[CodedWarning, ...]:
    warnings = []
    if skipped.unknown:
        names = ", ".join(sorted(skipped.unknown))
        warnings.append(CodedWarning(f"ignored {sum(skipped.unknown.values())} OBJ statements p3d does not read "
                                     f"({names}; the first on line {skipped.first_unknown}); free-form curves and "
                                     "surfaces are not part of the mass properties", "skipped-lines"))
    if skipped.garbled:
        assert skipped.first_garbled is not None
        number, words = skipped.first_garbled
        many = skipped.garbled > 1
        warnings.append(CodedWarning(f"skipped {skipped.garbled} line{'s that are' if many else ' that is'} no OBJ "
                                     f"statement ({'the first is ' if many else ''}line {number}: {_text(words)!r})",
                                     "skipped-lines"))
    return tuple(warnings)
