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

import warnings

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

#: Bytes of text parsed at a time by the fast path: small enough to stay in cache between the
#: few passes each chunk gets, large enough that the per-chunk overhead is nothing.
_ASCII_CHUNK = 1 << 22

#: The fast path's byte map: digits, sign and point stay; ``e``/``E`` become ``e`` (exponents);
#: whitespace and every other letter become a space; anything else becomes ``!``, which no
#: number contains, so that numpy's parser stops and the careful line parser takes over.
_NUMBER_BYTES = b"0123456789+-."
_LETTERS = bytes(range(ord("a"), ord("z") + 1)) + bytes(range(ord("A"), ord("Z") + 1))
_ASCII_TABLE = bytes(
    c if c in _NUMBER_BYTES else
    ord("e") if c in b"eE" else
    ord(" ") if c in _LETTERS or c in b" \t\n\r\x0b\x0c" else
    ord("!")
    for c in range(256))
#: Per facet: 'facet normal', 'outer loop', 3 x 'vertex', 'endloop', 'endfacet' hold 42
#: letters other than e, and 11 e's, each of which the map leaves as a lone word " e ".
_FACET_LETTERS, _FACET_LONE_ES = 42, 11
_SPACE, _E = ord(" "), ord("e")


def _load_ascii(raw: RawInput) -> MeshSource:
    blocks = _fast_ascii(raw)
    if blocks is None:
        data = raw.read_all()
        if b"\r" in data:
            data = data.replace(b"\r", b"")
        return array_source("stl-ascii", _parse_lines(raw.where, data), "float64")
    count = sum(len(b) for b in blocks)
    return MeshSource("stl-ascii", count, "float64", lambda: iter(blocks), None, ())


def _fast_ascii(raw: RawInput) -> list[np.ndarray] | None:
    """The triangles of a well-formed ASCII STL, parsed chunk by chunk at C speed.

    Returns ``(k, 3, 3)`` float64 blocks, or None whenever anything is unusual (a polygon, a
    stray word, a character outside numbers and keywords, no facets at all): the line parser
    then reads the file and names the line at fault. The numbers are the same either way:
    numpy's parser, like ``float``, rounds correctly.
    """
    blocks = []
    with raw.open() as f:
        tail = b""
        while True:
            piece = f.read(_ASCII_CHUNK)
            data = tail + piece if tail else piece
            if piece:
                # Cut after the last whole facet; the rest starts the next chunk.
                cut = data.rfind(b"endfacet")
                if cut == -1:
                    if len(data) > 4 * _ASCII_CHUNK:
                        return None             # no facet end in 16 MB: not for the fast path
                    tail = data
                    continue
                cut += len(b"endfacet")
                chunk, tail = data[:cut], data[cut:]
            else:
                chunk, tail = data, b""
            triangles = _chunk_triangles(chunk)
            if triangles is None:
                return None
            if len(triangles):
                blocks.append(triangles)
            if not piece:
                break
    return blocks or None


def _chunk_triangles(chunk: bytes) -> np.ndarray | None:
    """The triangles of whole facets of well-formed text; None when in doubt.

    Well-formed means: after the ``solid``/``endsolid`` lines, the letters are exactly those of
    one set of keywords per facet, and the numbers exactly 12 per facet (a normal and three
    vertices). A polygon, a stray word or a missing number breaks a count; any other character
    stops numpy's parser.
    """
    facets = chunk.count(b"endfacet")
    if facets == 0:
        return np.zeros((0, 3, 3)) if not _strip_solid_lines(chunk).strip() else None
    body = chunk
    mapped, letters = _map_ascii(body)
    if letters != _FACET_LETTERS * facets:
        # Most chunks hold no 'solid' line; those that do are stripped and counted again.
        body = _strip_solid_lines(chunk)
        if body is chunk:
            return None
        mapped, letters = _map_ascii(body)
        if letters != _FACET_LETTERS * facets:
            return None
    numbers_text = mapped.replace(b" e ", b"   ")
    lone = (np.count_nonzero(np.frombuffer(mapped, np.uint8) == _E)
            - np.count_nonzero(np.frombuffer(numbers_text, np.uint8) == _E))
    if lone != _FACET_LONE_ES * facets:
        return None
    try:
        with warnings.catch_warnings():
            # Older numpy warns and returns what it read so far; make that a failure too.
            warnings.simplefilter("error", DeprecationWarning)
            numbers = np.fromstring(numbers_text, dtype=np.float64, sep=" ")
    except (ValueError, DeprecationWarning):
        return None
    if numbers.size != 12 * facets:
        return None
    return numbers.reshape(facets, 4, 3)[:, 1:, :]     # drop the stored normals


def _map_ascii(body: bytes) -> tuple[bytes, int]:
    """``body`` through ``_ASCII_TABLE``, and how many letters other than e it held."""
    mapped = body.translate(_ASCII_TABLE)
    # Whitespace and letters other than e became spaces; whitespace was there before.
    spaces = np.count_nonzero(np.frombuffer(mapped, np.uint8) == _SPACE)
    return mapped, spaces - np.count_nonzero(np.frombuffer(body, np.uint8) <= _SPACE)


def _strip_solid_lines(data: bytes) -> bytes:
    """Remove ``solid NAME`` and ``endsolid NAME`` lines: names may hold anything, even numbers.

    'solid' occurs only in those few lines (any other line holding it fails the fast path's
    letter count afterwards), so cut around each occurrence rather than scan with a regex.
    """
    lower = data.find(b"solid")
    if lower == -1:
        return data
    pieces, pos = [], 0
    while lower != -1:
        line_start = data.rfind(b"\n", 0, lower) + 1
        line_end = data.find(b"\n", lower)
        line_end = len(data) if line_end == -1 else line_end
        pieces.append(data[pos:line_start])
        pos = line_end
        lower = data.find(b"solid", line_end)
    pieces.append(data[pos:])
    return b"".join(pieces)


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
