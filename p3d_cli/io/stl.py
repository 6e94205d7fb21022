"""STL, binary and ASCII.

Binary STL: an 80-byte header, a little-endian uint32 triangle count ``n``, then ``n`` records
of 50 bytes (normal, three corners as float32, a uint16 attribute). The header may begin with
``solid`` (many CAD exporters write that), so binary and ASCII are told apart by the size:
a binary file holds ``84 + 50 n`` bytes (trailing bytes are tolerated with a warning), never by
the first word (FACTS.md; trimesh 5.2 gets this wrong and returns an empty mesh). Binary files
are streamed in blocks, so memory stays far below the file's size.

ASCII STL: ``solid``/``endsolid`` blocks (several in one file are read as one mesh) of
``facet normal``/``outer loop``/``vertex``×3/``endloop``/``endfacet``. The stored normals are
ignored: the winding of the corners is what the integrals use.
"""

from __future__ import annotations

import re

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import BLOCK, MeshSource, array_source

_HEADER = 84
_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
assert _RECORD.itemsize == 50  # noqa: S101 - a layout fact, not input validation


def _binary_count(head: bytes) -> int | None:
    if len(head) < _HEADER:
        return None
    return int(np.frombuffer(head[80:84], "<u4")[0])


def _starts_with_solid(head: bytes) -> bool:
    return head.lstrip()[:5].lower() == b"solid"


def looks_like_stl(raw: RawInput) -> bool:
    """True when the bytes are a binary STL by size, or text starting with ``solid``."""
    head = raw.head(512)
    n = _binary_count(head)
    if n is not None and _HEADER + 50 * n == raw.size:
        return True
    return _starts_with_solid(head) and b"\0" not in head


def load(raw: RawInput) -> MeshSource:
    """Read a binary or ASCII STL.

    Raises
    ------
    FormatError
        Truncated file (a header claiming more triangles than the file holds), a file too
        short for the header, or malformed ASCII.
    InputError
        No triangles.
    """
    head = raw.head(512)
    n = _binary_count(head)
    if n is not None and _HEADER + 50 * n == raw.size:
        return _load_binary(raw, n, ())
    if _starts_with_solid(head) and b"\0" not in head[:256]:
        return _load_ascii(raw)
    if n is None:
        raise FormatError(raw.where, f"{raw.size} bytes is too short for a binary STL (84-byte header) and the "
                          "file is not ASCII STL (no leading 'solid')", "export the mesh again")
    expected = _HEADER + 50 * n
    if expected > raw.size:
        whole = (raw.size - _HEADER) // 50
        raise FormatError(raw.where, f"binary STL header claims {n} triangles ({expected} bytes) but the file "
                          f"has {raw.size} bytes (room for {max(whole, 0)})",
                          "the file is truncated or not an STL; export it again")
    extra = raw.size - expected
    warning = f"{extra} trailing bytes after the last of {n} triangles were ignored"
    return _load_binary(raw, n, (warning,))


def _load_binary(raw: RawInput, n: int, warnings) -> MeshSource:
    if n == 0:
        raise InputError(raw.where, "binary STL holds no triangles", "export the mesh again with its faces")

    def read_blocks():
        with raw.open() as f:
            f.seek(_HEADER)
            remaining = n
            while remaining:
                k = min(BLOCK, remaining)
                buf = f.read(50 * k)
                if len(buf) != 50 * k:
                    raise FormatError(raw.where, "file ended early while reading triangles",
                                      "the file changed while p3d read it, or is truncated")
                yield np.frombuffer(buf, _RECORD)["corners"]
                remaining -= k

    return MeshSource("stl-binary", n, "float32", read_blocks, None, tuple(warnings))


# --- ASCII -------------------------------------------------------------------------------

_SOLID_LINE = re.compile(rb"^[ \t]*(?:end)?solid\b[^\n]*$", re.MULTILINE | re.IGNORECASE)
_KEYWORDS = (b"endfacet", b"endloop", b"facet", b"normal", b"outer", b"loop", b"vertex")


def _load_ascii(raw: RawInput) -> MeshSource:
    data = raw.read_all()
    if b"\r" in data:
        data = data.replace(b"\r", b"")
    body = _strip_solid_lines(data)
    facets = body.count(b"endfacet")
    vertices = body.count(b"vertex")
    if facets and vertices == 3 * facets and body.count(b"facet") == 2 * facets:
        fast = _fast_numbers(body, facets)
        if fast is not None:
            return array_source("stl-ascii", fast, "float64")
    return array_source("stl-ascii", _parse_lines(raw.where, data), "float64")


def _strip_solid_lines(data: bytes) -> bytes:
    """Remove ``solid NAME`` and ``endsolid NAME`` lines: names may hold anything, even numbers."""
    return _SOLID_LINE.sub(b"", data) if len(data) < 4096 else _strip_solid_lines_fast(data)


def _strip_solid_lines_fast(data: bytes) -> bytes:
    # The regex would scan every byte; 'solid' occurs only in those few lines, so cut around them.
    pieces, pos = [], 0
    lower = data.find(b"solid")
    while lower != -1:
        line_start = data.rfind(b"\n", 0, lower) + 1
        line_end = data.find(b"\n", lower)
        line_end = len(data) if line_end == -1 else line_end
        pieces.append(data[pos:line_start])
        pos = line_end
        lower = data.find(b"solid", line_end)
    pieces.append(data[pos:])
    return b"".join(pieces)


def _fast_numbers(body: bytes, facets: int) -> np.ndarray | None:
    """All numbers of a well-formed file in one C-level parse; None to fall back to lines."""
    for word in _KEYWORDS:
        body = body.replace(word, b" ")
    numbers = np.fromstring(body, dtype=np.float64, sep=" ") if body.strip() else np.zeros(0)
    if numbers.size != 12 * facets:
        return None
    return numbers.reshape(facets, 4, 3)[:, 1:, :]


def _parse_lines(where: str, data: bytes) -> np.ndarray:
    """A careful line-by-line parse: polygons with more than three vertices become fans, and
    anything malformed gets its line number."""
    triangles: list[list[list[float]]] = []
    loop: list[list[float]] | None = None
    for number, line in enumerate(data.split(b"\n"), start=1):
        words = line.split()
        if not words:
            continue
        key = words[0].lower()
        if key == b"vertex":
            if loop is None:
                raise FormatError(f"{where}: line {number}", "'vertex' outside 'outer loop'",
                                  "the ASCII STL is malformed; export it again")
            try:
                if len(words) != 4:
                    raise ValueError
                loop.append([float(w) for w in words[1:]])
            except ValueError:
                text = line.decode("utf-8", "replace").strip()
                raise FormatError(f"{where}: line {number}", f"expected 'vertex X Y Z', found {text!r}",
                                  "the ASCII STL is malformed; export it again") from None
        elif key == b"outer":
            loop = []
        elif key == b"endloop":
            if loop is None or len(loop) < 3:
                raise FormatError(f"{where}: line {number}", "a facet with fewer than 3 vertices",
                                  "the ASCII STL is malformed; export it again")
            triangles.extend([loop[0], loop[i], loop[i + 1]] for i in range(1, len(loop) - 1))
            loop = None
        elif key in (b"facet", b"endfacet", b"solid", b"endsolid"):
            continue
        else:
            text = line.decode("utf-8", "replace").strip()[:60]
            raise FormatError(f"{where}: line {number}", f"unexpected {text!r} in ASCII STL",
                              "the file is corrupt or not an STL")
    if loop is not None:
        raise FormatError(where, "file ends inside a facet", "the file is truncated; export it again")
    if not triangles:
        raise InputError(where, "ASCII STL holds no facets", "export the mesh again with its faces")
    return np.array(triangles, dtype=np.float64)
