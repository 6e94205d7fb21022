"""The OBJ fast path: what exporters write, parsed chunk by chunk with a few C-level passes.

It handles one statement per line, known keywords and single-spaced face corners of one form
per line, with no Python object per line: numpy classifies every line by its first bytes, the
``v`` and ``f`` lines are cut out as runs, a sentinel is put after each line and all numbers are
parsed with one ``np.fromstring``; the sentinels give every line's count, so a malformed line
is detected, never silently shifted into its neighbour. numpy's number reading is held to the
grammar of ``p3d_cli.io.numbers`` (see there). Whenever a chunk's text is anything else, the
answer is None and the careful parser in ``p3d_cli.io.obj`` reads that chunk (and names the
line of an error): both accept the same inputs and give the same triangles.

The file is read in chunks of whole lines, so the peak memory is the arrays read (about 0.6
times the text: float64 vertices, and int32 vertex indices while they fit, kept chunk by
chunk) plus one chunk's temporaries, not several copies of the file.
"""

from __future__ import annotations

import re
from typing import Iterator

import numpy as np

from p3d_cli.io.numbers import fromstring, lone_sign, saturated
from p3d_cli.io.polygons import fan_triangles

#: Bytes of text parsed at a time: the temporaries (~10 bytes per byte of a chunk) stay small
#: beside the arrays read (4 MB chunks added 16 MB to the peak of a 39 MB file, and were no faster).
CHUNK = 1 << 20
#: Keywords of statements that carry nothing p3d needs (texture, normals, groups, materials, ...).
IGNORED = (b"vt", b"vn", b"vp", b"g", b"o", b"s", b"usemtl", b"mtllib", b"l", b"p")
#: A line's first two bytes -> the ignored keyword it must be (then followed by a space, a tab or
#: the line end).
_HEADS = {k[:2]: k for k in IGNORED if len(k) > 1}
_HEADS.update({k + end: k for k in IGNORED if len(k) == 1 for end in (b" ", b"\t", b"\n")})
_ENDS = (32, 9, 10)
_DIGITS_AND_SIGNS = b"0123456789+-"
_NL, _SPACE = 10, 32
#: A line continued on the next (the careful parser joins it, whitespace after the '\\' allowed).
CONTINUATION = re.compile(rb"\\[ \t\x0b\x0c]*\n")


def chunks_of(stream, size: int = CHUNK) -> Iterator[bytes]:
    """Pieces of ``stream`` that end at a newline (the last piece may not), CR made a newline."""
    tail = b""
    while True:
        piece = stream.read(size)
        if not piece:
            break
        data = tail + piece if tail else piece
        cut = data.rfind(b"\n") + 1
        if cut == 0:
            tail = data
            continue
        chunk, tail = data[:cut], data[cut:]
        yield _normalise(chunk)
    if tail:
        yield _normalise(tail)


def _normalise(chunk: bytes) -> bytes:
    if b"\r" in chunk:
        # CRLF (and old Mac CR) line endings: a bare CR is a line break too.
        chunk = chunk.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    return chunk


def parse_chunk(data: bytes, defined: int):
    """``(vertices, triangles, statements)`` of one chunk of whole lines, or None when some line
    is not of the plain forms handled here (the careful parser then reads this chunk).

    Parameters
    ----------
    data : bytes
        Whole lines (``chunks_of``), with no NUL byte and no ``\\`` continuation.
    defined : int
        Vertices defined before the chunk (relative indices count back from them).

    Returns
    -------
    vertices : (v, 3) float64
    triangles : (t, 3) int32 or int64
        0-based vertex indices, not yet checked against the vertex count (a relative index
        reaching before the first vertex comes out negative).
    statements : int
        Lines holding a statement (not blank, not only a comment), for the careful parser's
        count of stray lines.
    """
    size = len(data)
    array = np.frombuffer(data, dtype=np.uint8)
    breaks = np.flatnonzero(array == _NL)
    starts = np.concatenate(([0], breaks + 1))
    stops = np.concatenate((breaks, [size]))
    if starts[-1] >= size:       # the chunk ends with a newline: no last (empty) line
        starts, stops = starts[:-1], stops[:-1]
    # A line's first two bytes; past its end they read as '\n' (an empty line).
    padded = np.concatenate((array, np.full(8, _NL, dtype=np.uint8)))  # room to read keywords
    first, second = padded[starts], padded[starts + 1]
    second[first == _NL] = _NL
    is_vertex = (first == ord("v")) & (second == _SPACE)
    is_face = (first == ord("f")) & (second == _SPACE)
    other = ~(is_vertex | is_face)
    if other.any() and not _ignorable(padded, starts[other], first[other], second[other]):
        return None
    statements = len(starts) - int(np.count_nonzero(other & ((first == _NL) | (first == ord("#")))))
    vertices = _vertices(_cut(data, starts, stops, is_vertex), int(is_vertex.sum()))
    if vertices is None:
        return None
    face_count = int(is_face.sum())
    if not face_count:
        return vertices, np.zeros((0, 3), dtype=np.int32), statements
    parsed = faces(_cut(data, starts, stops, is_face), face_count)
    if parsed is None:
        return None
    corners, sizes = parsed
    if (sizes < 3).any():
        return None
    if (corners < 0).any():
        # Relative indices count back from the vertices defined before each face line.
        before = defined + np.repeat(np.cumsum(is_vertex)[is_face], sizes)
        corners = np.where(corners < 0, before + corners, corners - 1)
    else:
        corners -= 1
    return vertices, fan_triangles(_narrow(corners), sizes), statements


def _narrow(corners: np.ndarray) -> np.ndarray:
    """``corners`` as int32 when every index fits (any mesh under 2^31 vertices): the faces are
    the largest array an OBJ holds; an index out of range is found later either way."""
    if corners.size and -2**31 <= int(corners.min()) and int(corners.max()) < 2**31:
        return corners.astype(np.int32)
    return corners


def _ignorable(padded: np.ndarray, starts: np.ndarray, first: np.ndarray, second: np.ndarray) -> bool:
    """True when every line is blank, a ``#`` comment or an ignored statement, spelled exactly
    (``vt`` but not ``vtx``: an unknown keyword is the careful parser's, which warns of it)."""
    rest = (first != _NL) & (first != ord("#"))
    if not rest.any():
        return True
    starts = starts[rest]
    heads = first[rest].astype(np.int64) * 256 + second[rest]
    for head in np.unique(heads).tolist():
        keyword = _HEADS.get(bytes([head >> 8, head & 255]))
        if keyword is None:
            return False
        at = starts[heads == head]
        for k in range(2, len(keyword)):
            if (padded[at + k] != keyword[k]).any():
                return False
        if len(keyword) > 1 and not np.isin(padded[at + len(keyword)], _ENDS).all():
            return False
    return True


def _cut(data: bytes, starts: np.ndarray, stops: np.ndarray, chosen: np.ndarray) -> bytes:
    """The chosen lines, joined by newlines, copied as whole runs of consecutive lines."""
    edges = np.diff(np.concatenate(([0], chosen.view(np.int8), [0])))
    firsts = np.flatnonzero(edges == 1)
    lasts = np.flatnonzero(edges == -1) - 1
    return b"\n".join([data[a:b] for a, b in zip(starts[firsts].tolist(), stops[lasts].tolist())])


def _strip_keyword(text: bytes) -> bytes:
    """Lines that all start with a one-letter keyword and a space, without those two bytes
    (only at line starts: ``'v 1v 0 0'`` must keep its ``1v``)."""
    return b"  " + text[2:].replace(b"\nv ", b"\n  ").replace(b"\nf ", b"\n  ")


def _vertices(text: bytes, n: int) -> np.ndarray | None:
    if not n:
        return np.zeros((0, 3))
    # A NaN after every line marks where each line's numbers end.
    text = _strip_keyword(text).replace(b"\n", b" nan\n") + b" nan"
    try:
        numbers = fromstring(text, np.float64)
    except ValueError:
        return None
    del text
    if numbers.size % n:
        return None
    width = numbers.size // n
    if width not in (4, 5, 7):  # x y z, x y z w, x y z r g b; plus the sentinel
        return None
    table = numbers.reshape(n, width)
    if not np.isnan(table[:, -1]).all() or not np.isfinite(table[:, :-1]).all():
        return None  # uneven lines, or a literal NaN or infinity: let the careful parser look
    return np.ascontiguousarray(table[:, :3])


def faces(text: bytes, n: int):
    """``(corners, sizes)`` of ``n`` face lines: raw OBJ indices (1-based or negative) and
    vertices per face, or None when the lines are not of a form handled here."""
    words = text[2:].split(None, 1)
    first_corner = words[0] if words else b""  # an 'f' line with no corner: the careful parser names it
    slashes = first_corner.count(b"/")
    body = _strip_keyword(text)
    if slashes == 0:
        return _plain_faces(body, n)
    if slashes > 2 or b"\t" in text or b" /" in text:
        return None
    return _slashed_faces(text, body, n, first_corner)


def _parse_ints(text: bytes) -> np.ndarray | None:
    try:
        numbers = fromstring(text, np.int64)
    except ValueError:
        return None
    if saturated(numbers) or lone_sign(text):
        return None
    return numbers


def _plain_faces(body: bytes, n: int):
    # 0 is never a valid OBJ index, so a 0 after each line marks the line ends.
    numbers = _parse_ints(body.replace(b"\n", b" 0\n") + b" 0")
    if numbers is None:
        return None
    ends = np.flatnonzero(numbers == 0)
    if ends.size != n or ends[-1] != numbers.size - 1:
        return None
    sizes = np.diff(ends, prepend=-1) - 1
    return numbers[numbers != 0], sizes


def _slashed_faces(text: bytes, body: bytes, n: int, first_corner: bytes):
    """Corners with slashes, all of the first corner's form (``a/b``, ``a/b/c``, ``a//c``,
    ``a/b/``): with digits and signs deleted, every line must read ``f`` and then `` /`` (or
    `` //``) once per corner, single-spaced; each corner then holds at most its form's count of
    numbers, so a line holding exactly that count times its corners holds no other form."""
    mark = b"//" if first_corner.count(b"/") == 2 else b"/"
    parts = first_corner.split(b"/")
    per_corner = sum(1 for p in parts if p)
    if not parts[0] or per_corner < 2 or (mark == b"//" and per_corner == 2 and
                                                              (b"// " in text or b"//\n" in text or
                                                               text.endswith(b"//"))):
        return None   # 'a//' (one number) and 'a/' (no corner) forms: for the careful parser
    pattern = text.translate(None, _DIGITS_AND_SIGNS)
    if pattern.replace(b" " + mark, b"") != b"f\n" * (n - 1) + b"f":
        return None
    line_ends = np.flatnonzero(np.frombuffer(pattern + b"\n", dtype=np.uint8) == _NL)
    sizes = (np.diff(line_ends, prepend=-1) - 2) // (1 + len(mark))
    numbers = _parse_ints(body.replace(b"/", b" ").replace(b"\n", b" 0\n") + b" 0")
    if numbers is None:
        return None
    ends = np.flatnonzero(numbers == 0)   # 0 is no valid index, texture or normal number
    if ends.size != n or ends[-1] != numbers.size - 1:
        return None
    counts = np.diff(ends, prepend=-1) - 1
    if not (counts == per_corner * sizes).all():
        return None
    line_start = ends - counts
    owner = np.repeat(np.arange(n), sizes)
    within = np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    return numbers[line_start[owner] + per_corner * within], sizes
