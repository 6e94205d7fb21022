"""Wavefront OBJ: ``v`` vertices and ``f`` faces; everything else is ignored.

Faces are polygons of any size, split as a fan from their first vertex (``v0, vi, vi+1``,
the convention of reference.json). A face corner is ``a``, ``a/b``, ``a//c`` or ``a/b/c``;
only ``a`` matters. Indices are 1-based, or negative: ``-1`` is the last vertex defined
*before that face line* (FACTS.md, "Formats in the wild"). Coordinates are parsed as float64
(the decimal text rounded once), and nothing is merged or repaired.

Two parsers share one meaning. The fast path handles what exporters write (one statement per
line, known keywords, single-spaced faces) with a handful of C-level passes and no Python
object per line: numpy classifies every line by its first two bytes, the ``v`` and ``f`` lines
are cut out as runs, a sentinel is put after each line and all numbers are parsed with one
``np.fromstring``; the sentinels give every line's count, so a malformed line is detected,
never silently shifted into its neighbour. Anything the fast path does not recognise, and
every error, goes to the careful line-by-line parser, which reports the line number.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source

#: Statements that carry nothing p3d needs (texture, normals, groups, materials, lines, points).
_IGNORED = {b"vt", b"vn", b"vp", b"g", b"o", b"s", b"usemtl", b"mtllib", b"l", b"p"}
#: First two bytes of lines the fast path understands (``b""`` is a blank line).
_FAST_HEADS = {b"v ", b"f ", b"vt", b"vn", b"vp", b"g ", b"g", b"o ", b"o", b"s ", b"s", b"us", b"mt",
               b"l ", b"p ", b""}
_HINT = "fix the file or export it again"


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
    data = raw.read_all()
    if b"\r" in data:
        # CRLF (and old Mac CR) line endings: a bare CR is a line break too.
        data = data.replace(b"\r\n", b"\n").replace(b"\r", b"\n")
    fast = None if b"\\\n" in data else _parse_fast(data)
    if fast is None:
        vertices, faces, warnings = _parse_lines(raw.where, data)
    else:
        vertices, faces = fast
        warnings = ()
    if len(faces) == 0:
        raise InputError(raw.where, f"no faces (the file defines {len(vertices)} vertices and no 'f' lines)",
                         "export the mesh with its faces, not as a point cloud")
    return indexed_source("obj", vertices, faces, "float64", warnings)


# --- polygons ----------------------------------------------------------------------------

def fan_triangles(corners: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Split polygons into fans from their first vertex, keeping polygon order.

    Parameters
    ----------
    corners : (sum(sizes),) integer
        The polygons' vertex indices, one polygon after the other.
    sizes : (n,) integer
        Vertices per polygon, each at least 3.

    Returns
    -------
    (sum(sizes - 2), 3) int64
        Triangles ``(v0, vi, vi+1)`` for ``i = 1 .. k-2`` of each polygon, in order.
    """
    corners = np.asarray(corners, dtype=np.int64)
    sizes = np.asarray(sizes, dtype=np.int64)
    if len(sizes) == 0:
        return np.zeros((0, 3), dtype=np.int64)
    k = int(sizes[0])
    if (sizes == k).all():
        # All polygons the same size (the common case: all triangles or all quads).
        polygons = corners.reshape(len(sizes), k)
        if k == 3:
            return polygons
        tris = np.empty((len(sizes), k - 2, 3), dtype=np.int64)
        tris[:, :, 0] = polygons[:, :1]
        tris[:, :, 1] = polygons[:, 1:-1]
        tris[:, :, 2] = polygons[:, 2:]
        return tris.reshape(-1, 3)
    starts = np.cumsum(sizes) - sizes
    per = sizes - 2
    owner = np.repeat(np.arange(len(sizes)), per)
    first = starts[owner]
    step = np.arange(int(per.sum())) - np.repeat(np.cumsum(per) - per, per)
    return np.stack([corners[first], corners[first + step + 1], corners[first + step + 2]], axis=1)


# --- fast path ---------------------------------------------------------------------------

def _parse_fast(data: bytes):
    """``(vertices, faces)`` for a plain, well-formed file, else None (use ``_parse_lines``).

    Lines are classified by their first two bytes with numpy, and the ``v`` and ``f`` lines
    are cut out of the file as a few contiguous runs, so no Python object is made per line.
    """
    size = len(data)
    array = np.frombuffer(data, dtype=np.uint8)
    breaks = np.flatnonzero(array == 10)
    starts = np.concatenate(([0], breaks + 1))
    stops = np.concatenate((breaks, [size]))
    if size < 2:
        return None
    # A line's first two bytes; past the end of the file they read as '\n' (an empty line).
    first = array[np.minimum(starts, size - 1)]
    second = array[np.minimum(starts + 1, size - 1)]
    second[starts + 1 >= size] = 10
    first[starts >= size] = 10
    is_vertex = (first == ord("v")) & (second == ord(" "))
    is_face = (first == ord("f")) & (second == ord(" "))
    other = ~(is_vertex | is_face)
    if other.any():
        seen = np.bincount(first[other].astype(np.int64) * 256 + second[other], minlength=65536)
        for pair in np.flatnonzero(seen).tolist():
            head = bytes([pair >> 8, pair & 255]).rstrip(b"\n")
            if head not in _FAST_HEADS and head[:1] != b"#":
                return None
    vertices = _fast_vertices(_cut(data, starts, stops, is_vertex), int(is_vertex.sum()))
    if vertices is None:
        return None
    face_count = int(is_face.sum())
    if not face_count:
        return vertices, np.zeros((0, 3), dtype=np.int64)
    parsed = _fast_faces(_cut(data, starts, stops, is_face), face_count)
    if parsed is None:
        return None
    corners, sizes = parsed
    if (sizes < 3).any():
        return None
    if (corners < 0).any():
        # Relative indices count back from the vertices defined before each face line.
        defined = np.repeat(np.cumsum(is_vertex)[is_face], sizes)
        corners = np.where(corners < 0, defined + corners, corners - 1)
    else:
        corners = corners - 1
    if len(corners) and (corners.min() < 0 or corners.max() >= len(vertices)):
        return None  # the careful parser names the line and the index
    return vertices, fan_triangles(corners, sizes)


def _cut(data: bytes, starts: np.ndarray, stops: np.ndarray, chosen: np.ndarray) -> bytes:
    """The chosen lines, joined by newlines, copied as whole runs of consecutive lines."""
    edges = np.diff(np.concatenate(([0], chosen.view(np.int8), [0])))
    firsts = np.flatnonzero(edges == 1)
    lasts = np.flatnonzero(edges == -1) - 1
    return b"\n".join([data[a:b] for a, b in zip(starts[firsts].tolist(), stops[lasts].tolist())])


def _fast_vertices(text: bytes, n: int) -> np.ndarray | None:
    if not n:
        return np.zeros((0, 3))
    # A NaN after every line marks where each line's numbers end.
    text = (text.replace(b"\n", b" nan\n") + b" nan").replace(b"v ", b"  ")
    try:
        numbers = np.fromstring(text, dtype=np.float64, sep=" ")
    except ValueError:
        return None
    if numbers.size % n:
        return None
    width = numbers.size // n
    if width not in (4, 5, 7):  # x y z, x y z w, x y z r g b; plus the sentinel
        return None
    table = numbers.reshape(n, width)
    if not np.isnan(table[:, -1]).all() or np.isnan(table[:, :-1]).any():
        return None  # uneven lines, or a literal NaN: let the careful parser look
    return np.ascontiguousarray(table[:, :3])


def _fast_faces(raw_text: bytes, n: int):
    """``(corners, sizes)``: raw OBJ indices (1-based or negative) and vertices per face."""
    if b"/" not in raw_text:
        # 0 is never a valid OBJ index, so a 0 after each line marks the line ends.
        text = (raw_text.replace(b"\n", b" 0\n") + b" 0").replace(b"f ", b"  ")
        try:
            numbers = np.fromstring(text, dtype=np.int64, sep=" ")
        except ValueError:
            return None
        ends = np.flatnonzero(numbers == 0)
        if ends.size != n or ends[-1] != numbers.size - 1:
            return None
        sizes = np.diff(ends, prepend=-1) - 1
        return numbers[numbers != 0], sizes
    strided = _strided_corners(raw_text, n)
    if strided is not None:
        return strided
    # Corners like a/b: every '/' becomes a 0 and every line ends with three 0s. Within a
    # corner zeros come in runs of 1 or 2 ('/' or '//'), so runs of 3 are exactly the line
    # ends, and a corner's vertex index is a non-zero that follows a non-zero or a line end.
    text = (raw_text.replace(b"\n", b" 0 0 0\n") + b" 0 0 0").replace(b"f ", b"  ").replace(b"/", b" 0 ")
    try:
        numbers = np.fromstring(text, dtype=np.int64, sep=" ")
    except ValueError:
        return None
    zero = numbers == 0
    uniform = _uniform_corners(numbers, zero, n)
    if uniform is not None:
        # Every whitespace-separated word must be exactly one corner (catches 'f 1/ 2/3').
        words = raw_text.count(b" ")
        if words not in (uniform[0].size, uniform[0].size + n) or b"\t" in raw_text:
            return None
        return uniform
    edges = np.diff(np.concatenate(([0], zero.view(np.int8), [0])))
    run_starts = np.flatnonzero(edges == 1)
    run_stops = np.flatnonzero(edges == -1)
    lengths = run_stops - run_starts
    line_end = lengths == 3
    if (lengths > 3).any() or line_end.sum() != n or run_stops[-1] != numbers.size:
        return None
    first = ~zero
    first[1:] &= ~zero[:-1]
    after_line = run_stops[line_end]
    first[after_line[after_line < numbers.size]] = True
    first[0] = not zero[0]
    positions = np.flatnonzero(first)
    # Every whitespace-separated word must be exactly one corner (catches 'f 1/ 2/3').
    words = raw_text.count(b" ")
    if words not in (positions.size, positions.size + n) or b"\t" in raw_text:
        return None
    line_of = np.searchsorted(run_starts[line_end], positions)
    sizes = np.bincount(line_of, minlength=n)
    return numbers[positions], sizes


def _strided_corners(raw_text: bytes, n: int):
    """All faces alike with ``a/b/c`` or ``a//c`` corners: drop the slashes, parse every number
    and keep every second or third. Counting words, slashes and ``//`` proves every corner has
    the form of the first (a corner has at most three numbers and at most one ``//``)."""
    first = raw_text[2:raw_text.find(b"\n") if b"\n" in raw_text else len(raw_text)].split()
    if not first or b"\t" in raw_text:
        return None
    parts = first[0].split(b"/")
    if len(parts) != 3:
        return None  # 'a/b' could hide a mix of 'a' and 'a/b/c': use the marker parse
    stride = 2 if parts[1] == b"" else 3
    text = (raw_text.replace(b"\n", b" 0\n") + b" 0").replace(b"f ", b"  ").replace(b"/", b" ")
    try:
        numbers = np.fromstring(text, dtype=np.int64, sep=" ")
    except ValueError:
        return None
    if numbers.size % n:
        return None
    width = numbers.size // n
    if (width - 1) % stride or width < 1 + 3 * stride:
        return None
    table = numbers.reshape(n, width)
    if (table[:, -1] != 0).any() or not table[:, :-1].all():
        return None
    k = (width - 1) // stride
    corners = n * k
    doubles = raw_text.count(b"//")
    if raw_text.count(b"/") != 2 * corners or doubles != (corners if stride == 2 else 0):
        return None
    if raw_text.count(b" ") not in (corners, corners + n):
        return None
    return table[:, :-1:stride].ravel(), np.full(n, k, dtype=np.int64)


def _uniform_corners(numbers: np.ndarray, zero: np.ndarray, n: int):
    """The common case of ``_fast_faces``: every line has the first line's shape (same corner
    count and form), checked by comparing all lines' zero patterns at once."""
    if numbers.size % n:
        return None
    width = numbers.size // n
    pattern = zero[:width]
    if width < 4 or not pattern[-3:].all() or pattern[-4] or pattern[0]:
        return None
    inner = pattern[:-3]
    if (inner[:-2] & inner[1:-1] & inner[2:]).any():
        return None
    if not (zero.reshape(n, width) == pattern).all():
        return None
    columns = np.flatnonzero(~inner & np.concatenate(([True], inner[:-1] == 0)))
    return numbers.reshape(n, width)[:, columns].ravel(), np.full(n, columns.size, dtype=np.int64)


# --- careful path ------------------------------------------------------------------------

def _statements(data: bytes):
    """``(line number, words)`` per statement, joining ``\\`` continuations, dropping comments."""
    pending: list[bytes] = []
    start = 0
    for number, line in enumerate(data.split(b"\n"), start=1):
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


def _parse_lines(where: str, data: bytes):
    """Line by line, with line numbers in every error. Returns vertices, faces, warnings."""
    vertices: list[list[float]] = []
    corners: list[int] = []
    sizes: list[int] = []
    face_line: list[int] = []
    unknown: Counter = Counter()
    for number, words in _statements(data):
        key = words[0]
        if key == b"v":
            try:
                if len(words) not in (4, 5, 7):
                    raise ValueError
                vertices.append([float(w) for w in words[1:4]])
                [float(w) for w in words[4:]]
            except ValueError:
                raise FormatError(f"{where}: line {number}", f"expected 'v X Y Z [W]', found {_text(words)!r}",
                                  _HINT) from None
        elif key == b"f":
            if len(words) < 4:
                raise FormatError(f"{where}: line {number}",
                                  f"a face needs at least 3 vertices, found {_text(words)!r}", _HINT)
            for word in words[1:]:
                parts = word.split(b"/")
                try:
                    shape_ok = len(parts) == 1 or (len(parts) == 2 and parts[1]) or (len(parts) == 3 and parts[2])
                    if not shape_ok or any(p and int(p) == 0 for p in parts[1:]):
                        raise ValueError
                    index = int(parts[0])
                except ValueError:
                    raise FormatError(f"{where}: line {number}",
                                      f"bad face corner {word.decode('utf-8', 'replace')!r} (expected a, a/b, "
                                      "a//c or a/b/c with non-zero integers)", _HINT) from None
                if index == 0:
                    raise FormatError(f"{where}: line {number}", "face index 0 (OBJ indices start at 1)", _HINT)
                if index < 0:
                    resolved = len(vertices) + index
                    if resolved < 0:
                        raise FormatError(f"{where}: line {number}",
                                          f"relative face index {index} reaches before the first vertex "
                                          f"(only {len(vertices)} defined before this line)", _HINT)
                    corners.append(resolved)
                else:
                    corners.append(index - 1)
            sizes.append(len(words) - 1)
            face_line.append(number)
        elif key in _IGNORED:
            continue
        elif key[:1].isalpha():
            unknown[key.decode("utf-8", "replace")] += 1
        else:
            raise FormatError(f"{where}: line {number}", f"unexpected {_text(words)!r} in an OBJ file",
                              "the file is corrupt or not an OBJ")
    vertex_array = np.array(vertices, dtype=np.float64).reshape(-1, 3)
    corner_array = np.array(corners, dtype=np.int64)
    if corner_array.size:
        bad = np.flatnonzero(corner_array >= len(vertex_array))
        if bad.size:
            face = int(np.searchsorted(np.cumsum(sizes), bad[0], side="right"))
            raise FormatError(f"{where}: line {face_line[face]}",
                              f"face index {int(corner_array[bad[0]]) + 1} is out of range: the file defines "
                              f"{len(vertex_array)} vertices", "fix the face or export the mesh again")
    warnings = []
    if unknown:
        names = ", ".join(sorted(unknown))
        warnings.append(f"ignored {sum(unknown.values())} OBJ statements p3d does not read ({names}); "
                        "free-form curves and surfaces are not part of the mass properties")
    return vertex_array, fan_triangles(corner_array, np.array(sizes, dtype=np.int64)), tuple(warnings)
