"""ASCII STL: one grammar, a fast path and a careful parser that accept exactly the same files.

The grammar, line by line (blank lines anywhere, words separated by any whitespace, keywords in
any case): ``solid [name]`` and ``endsolid [name]`` lines between facets (several solids in one
file are read as one mesh); each facet is the lines ``facet normal NX NY NZ``, ``outer loop``,
three or more ``vertex X Y Z`` (a polygon, split as a fan), ``endloop``, ``endfacet``. Vertex
numbers follow ``p3d_cli.io.numbers``. The stored normal is not used (the winding of the corners
is what the integrals use), so whatever follows ``facet`` is not read: exporters write
``+inf``, ``nan`` or words there (PrusaSlicer's test file ``20mmbox-nonstandard.stl``), and
such files are read, as are words after ``outer loop``, ``endloop`` and ``endfacet``. A file
whose last line is not ``endsolid`` is read with a warning (it may be truncated after a whole
facet).

The fast path parses whole chunks of triangle facets at C speed. Instead of trusting numpy with
the structure, it finds every word with a few vectorised passes, and checks that the words are
exactly, in order, the 21 of a triangle facet (keywords spelled out, three numbers after
``normal`` and after each ``vertex``) and that the lines break exactly before ``facet``,
``outer``, ``vertex``, ``endloop`` and ``endfacet``; only then are the numbers parsed, all at
once. Anything else (a polygon, a stray word, another layout) goes to the careful parser.
"""

from __future__ import annotations

from array import array

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.numbers import fromstring, to_float
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, array_source
from p3d_cli.warning_codes import CodedWarning

#: Bytes of text parsed at a time by the fast path: small enough to stay in cache between the
#: few passes each chunk gets, large enough that the per-chunk overhead is nothing.
CHUNK = 1 << 22
_HINT = "the ASCII STL is malformed; export it again"

#: The number parse's byte map: digits, sign and point stay; ``e``/``E`` become ``e``
#: (exponents); whitespace and every other letter become a space; anything else becomes ``!``,
#: which no number contains, so that numpy's parser stops.
_LETTERS = bytes(range(ord("a"), ord("z") + 1)) + bytes(range(ord("A"), ord("Z") + 1))
_WHITESPACE = b" \t\n\r\x0b\x0c"
_PARSE_TABLE = bytes(
    c if c in b"0123456789+-." else ord("e") if c in b"eE" else
    ord(" ") if c in _LETTERS or c in _WHITESPACE else ord("!") for c in range(256))
#: Bytes a number word may start with.
_NUMBER_START = np.zeros(256, dtype=bool)
_NUMBER_START[list(b"0123456789+-.")] = True

#: The words of one triangle facet: a keyword, or None for a number; and whether a line break
#: comes before the word.
_FACET = [(b"facet", 1), (b"normal", 0), (None, 0), (None, 0), (None, 0), (b"outer", 1), (b"loop", 0)]
_FACET += [(b"vertex", 1), (None, 0), (None, 0), (None, 0)] * 3 + [(b"endloop", 1), (b"endfacet", 1)]
_WORDS = len(_FACET)
#: The words of a facet that start a line, but the first (as indices of the following word).
_BREAKS = np.array([i for i, (_, brk) in enumerate(_FACET) if brk][1:] + [_WORDS])
#: (column, offset) of each 'e' in a facet's keywords.
_E_COLUMNS, _E_OFFSETS = (np.array(v) for v in zip(*[(column, k) for column, (kw, _) in enumerate(_FACET) if kw
                                                       for k, c in enumerate(kw) if c == ord("e")]))

def _spelling(keyword: bytes) -> tuple[int, int, int]:
    """``(expected, mask, lower)`` for comparing the 8 bytes at a keyword with it: the keyword's
    bytes are kept by the mask and folded to lower case by setting their bit 5 (only upper-case
    letters fold onto lower-case ones)."""
    n = len(keyword)
    expected = int.from_bytes(keyword.ljust(8, b"\0"), "little")
    mask = int.from_bytes(b"\xff" * n + b"\0" * (8 - n), "little")
    lower = int.from_bytes(b"\x20" * n + b"\0" * (8 - n), "little")
    return expected, mask, lower


_KEYWORD_COLUMNS = np.array([i for i, (kw, _) in enumerate(_FACET) if kw])
_KEYWORD_LENGTHS = np.array([len(kw) for kw, _ in _FACET if kw])
_EXPECTED, _MASKS, _LOWER = (np.array(column, dtype=np.uint64)
                             for column in zip(*(_spelling(kw) for kw, _ in _FACET if kw)))
_NUMBER_COLUMNS = np.array([i for i, (kw, _) in enumerate(_FACET) if kw is None])
#: Letters of one facet's keywords other than e (these are blanked by the parse map).
_FACET_LETTERS = sum(len(kw) - kw.count(b"e") for kw, _ in _FACET if kw)


def load_ascii(raw: RawInput) -> MeshSource:
    """Read an ASCII STL (see the module docstring for the grammar).

    Raises
    ------
    FormatError
        A malformed line (with its number), or a file ending inside a facet.
    InputError
        No facets.
    """
    warnings = () if _ends_with_endsolid(raw) else (
        CodedWarning("the ASCII STL does not end with an 'endsolid' line: the file may be truncated", "reader"),)
    blocks = _fast(raw)
    if blocks is None:
        with raw.open() as stream:
            triangles = parse_lines(raw.where, stream)
        return array_source("stl-ascii", triangles, "float64", warnings)
    count = sum(len(b) for b in blocks)
    return MeshSource("stl-ascii", count, "float64", lambda: iter(blocks), None, warnings)


def _ends_with_endsolid(raw: RawInput) -> bool:
    with raw.open() as stream:
        stream.seek(max(raw.size - 4096, 0))
        tail = stream.read()
    lines = [line for line in tail.split(b"\n") if line.strip()]
    return bool(lines) and lines[-1].split()[0].lower() == b"endsolid"


def _fast(raw: RawInput) -> list[np.ndarray] | None:
    """``(k, 3, 3)`` float64 blocks of a file of triangle facets, or None when in doubt."""
    blocks = []
    with raw.open() as stream:
        tail = b""
        while True:
            piece = stream.read(CHUNK)
            data = tail + piece if tail else piece
            if piece:
                # Cut after the line of the last 'endfacet'; the rest starts the next chunk.
                cut = data.rfind(b"endfacet")
                cut = -1 if cut == -1 else data.find(b"\n", cut)
                if cut == -1:
                    if len(data) > 4 * CHUNK:
                        return None             # no facet end in 16 MB: not for the fast path
                    tail = data
                    continue
                chunk, tail = data[:cut + 1], data[cut + 1:]
            else:
                chunk, tail = data, b""
            triangles = chunk_triangles(chunk)
            if triangles is None:
                return None
            if len(triangles):
                blocks.append(triangles)
            if not piece:
                break
    return blocks or None


def chunk_triangles(chunk: bytes) -> np.ndarray | None:
    """The triangles of a chunk of whole lines starting at a line start, or None."""
    found = _triangles(chunk)
    if found is None and b"solid" in chunk:
        body = _strip_solid_lines(chunk)    # most chunks hold no 'solid' line: look only on failure
        found = None if body is None else _triangles(body)
    return found


def _triangles(body: bytes) -> np.ndarray | None:
    raw = np.frombuffer(body, np.uint8)
    found = _word_starts(raw)
    if found is None:
        return np.zeros((0, 3, 3)) if not body.strip() else None
    positions, spaces = found
    facets = positions.size // _WORDS
    table = positions.reshape(facets, _WORDS)
    if not _keywords_ok(body, raw, table):
        return None
    text = bytearray(body.translate(_PARSE_TABLE))
    mapped = np.frombuffer(text, np.uint8)
    # Whitespace and letters other than e became spaces: as many letters as the keywords have.
    if np.count_nonzero(mapped == 32) - spaces != _FACET_LETTERS * facets:
        return None     # a letter inside a number word ('1x'): every letter must be a keyword's
    mapped[table[:, _E_COLUMNS] + _E_OFFSETS] = 32   # the keywords' own e's are no exponents
    try:
        numbers = fromstring(bytes(text), np.float64)
    except ValueError:
        return None
    if numbers.size != 12 * facets or not np.isfinite(numbers).all():
        return None
    return numbers.reshape(facets, 4, 3)[:, 1:, :]     # drop the stored normals


def _word_starts(raw: np.ndarray) -> tuple[np.ndarray, int] | None:
    """Where the words start and how many whitespace bytes there are, if the words and line
    breaks are exactly those of whole triangle facets (blank lines before the first word and
    after the last aside); else None. Bytes up to 32 count as whitespace here: the control
    characters among them stop the number parse later.

    There must be 21 words per facet, and the lines must break exactly before the words 0, 5,
    7, 11, 15, 19 and 20 of each facet: the word following each newline is found by a binary
    search among the word starts.
    """
    if not raw.size:
        return None
    space = raw <= 32
    spaces = int(np.count_nonzero(space))
    start = np.empty_like(space)
    start[0] = not space[0]
    np.greater(space[:-1], space[1:], out=start[1:])     # a space, then no space
    positions = np.flatnonzero(start)
    facets = positions.size // _WORDS
    if not facets or positions.size != facets * _WORDS:
        return None
    following = np.searchsorted(positions, np.flatnonzero(np.equal(raw, 10, out=space)))
    inner = following[(following > 0) & (following < positions.size)]
    if inner.size != facets * _BREAKS.size - 1:
        return None
    expected = (np.arange(facets)[:, None] * _WORDS + _BREAKS).ravel()[:-1]
    return (positions, spaces) if (inner == expected).all() else None


def _keywords_ok(body: bytes, raw: np.ndarray, table: np.ndarray) -> bool:
    """Every keyword word is exactly its keyword (in any case) and every other word starts like
    a number. Eight bytes at each keyword are compared at once through an overlapping uint64
    view of the text (element ``i`` is bytes ``i .. i+7``), all keyword columns together."""
    last = len(body) - 8
    if last < 0:
        return False
    if not _NUMBER_START[raw[table[:, _NUMBER_COLUMNS]]].all():
        return False
    view = np.ndarray((last + 1,), dtype="<u8", buffer=body, offset=0, strides=(1,))
    at = table[:, _KEYWORD_COLUMNS]
    clipped = np.minimum(at, last)      # a word too close to the end for its keyword fails
    bytes8 = view[clipped]
    bytes8 &= _MASKS
    bytes8 |= _LOWER
    if (bytes8 != _EXPECTED).any():
        return False
    at += _KEYWORD_LENGTHS                  # the word must end there ('vertexe' is no keyword)
    inside = at < raw.size
    np.minimum(at, raw.size - 1, out=clipped)
    return not ((raw[clipped] > 32) & inside).any()


def _strip_solid_lines(data: bytes) -> bytes | None:
    """``data`` without its ``solid NAME`` and ``endsolid NAME`` lines (names may hold anything,
    even numbers), or None when such a line is not between facets.

    'solid' occurs only in those few lines (any other word holding it fails the word checks
    afterwards), so cut around each occurrence rather than scan with a regex.
    """
    found = data.find(b"solid")
    if found == -1:
        return data
    pieces, pos = [], 0
    while found != -1:
        line_start = data.rfind(b"\n", 0, found) + 1
        line_end = data.find(b"\n", found)
        line_end = len(data) if line_end == -1 else line_end
        first = data[line_start:line_end].split(None, 1)[0].lower()
        before = data[pos:line_start].rstrip()
        if first not in (b"solid", b"endsolid") or (before and before[-8:].lower() != b"endfacet"):
            return None
        pieces.append(data[pos:line_start])
        pos = line_end
        found = data.find(b"solid", line_end)
    pieces.append(data[pos:])
    return b"".join(pieces)


# --- careful path ------------------------------------------------------------------------

def _lines(stream):
    number = 0
    for line in stream:
        number += 1
        yield number, line.replace(b"\r", b" ")


def parse_lines(where: str, stream) -> np.ndarray:
    """A careful line-by-line parse of the grammar: polygons with more than three vertices
    become fans, and anything malformed gets its line number."""
    corners = array("d")
    state = "outside"
    loop: list = []
    for number, line in _lines(stream):
        words = line.split()
        if not words:
            continue
        key = words[0].lower()
        at = f"{where}: line {number}"
        if key in (b"solid", b"endsolid"):
            if state != "outside":
                raise FormatError(at, f"'{key.decode()}' inside a facet", _HINT)
        elif key == b"facet":
            # The normal (whatever follows 'facet') is never used, so it is not read.
            _expect(state == "outside", at, "'facet' inside a facet")
            state = "facet"
        elif key == b"outer":
            _expect(state == "facet" and len(words) >= 2 and words[1].lower() == b"loop", at,
                    f"expected 'outer loop' after 'facet normal', found {_show(line)!r}")
            state, loop = "loop", []
        elif key == b"vertex":
            _expect(state == "loop", at, "'vertex' outside 'outer loop'")
            loop.append(_numbers(at, words, 1, "vertex X Y Z"))
        elif key == b"endloop":
            _expect(state == "loop", at, f"unexpected {_show(line)!r} in ASCII STL")
            _expect(len(loop) >= 3, at, "a facet with fewer than 3 vertices")
            state = "endloop"
        elif key == b"endfacet":
            _expect(state == "endloop", at, f"unexpected {_show(line)!r} in ASCII STL")
            for i in range(1, len(loop) - 1):
                corners.extend(loop[0] + loop[i] + loop[i + 1])
            state = "outside"
        else:
            raise FormatError(at, f"unexpected {_show(line)!r} in ASCII STL", "the file is corrupt or not an STL")
    if state != "outside":
        raise FormatError(where, "file ends inside a facet", "the file is truncated; export it again")
    if not corners:
        raise InputError(where, "ASCII STL holds no facets", "export the mesh again with its faces")
    return np.frombuffer(corners, dtype=np.float64).reshape(-1, 3, 3).copy()


def _show(line: bytes) -> str:
    return line.decode("utf-8", "replace").strip()[:60]


def _expect(condition: bool, where: str, what: str) -> None:
    if not condition:
        raise FormatError(where, what, _HINT)


def _numbers(where: str, words: list[bytes], skip: int, form: str) -> list[float]:
    """The three numbers after the first ``skip`` words, checked to be the whole line."""
    try:
        if len(words) != skip + 3:
            raise ValueError
        return [to_float(w) for w in words[skip:]]
    except ValueError:
        raise FormatError(where, f"expected {form!r} with finite decimal numbers, found "
                          f"{_show(b' '.join(words))!r}", _HINT) from None
