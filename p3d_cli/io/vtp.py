"""VTK PolyData: XML ``.vtp`` and legacy ``.vtk`` files whose dataset is ``POLYDATA``.

meshio (5.3) reads neither: it has no PolyData reader for XML, and its legacy reader refuses
``DATASET POLYDATA``. Both are read here, following the VTK file formats document (VTK User's
Guide, "VTK File Formats": the legacy format, and the XML formats with their ``ascii``,
``binary`` (base64) and ``appended`` (raw or base64) data, optionally zlib-compressed in
blocks by ``vtkZLibDataCompressor``).

Polygons (``Polys`` / ``POLYGONS``) are split as fans from their first vertex and triangle
strips (``Strips`` / ``TRIANGLE_STRIPS``) into their triangles, every second one reversed so
that the strip keeps one orientation (the VTK convention). Vertices and lines hold no volume
and are left out, with a warning. Several pieces are read as one mesh. Points are integrated as
stored (float32 or float64).

Legacy files written by VTK 9 carry ``METADATA`` blocks (array ranges, component names, ended
by a blank line) after their arrays: they are read past. Every count and index is checked
before use (a cell size of -1, a count beyond the file, an index of ``1e20`` or ``nan`` in a
float array are refused), and every zlib block is inflated to exactly the size the file
declares for it, all blocks together to at most ``p3d_cli.io.limits.MAX_INFLATED`` bytes.
"""

from __future__ import annotations

import base64
import binascii
import re
from xml.etree import ElementTree

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.limits import check_declared, inflate
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source
from p3d_cli.warning_codes import CodedWarning

_TYPES = {"int8": "i1", "uint8": "u1", "int16": "i2", "uint16": "u2", "int32": "i4", "uint32": "u4",
          "int64": "i8", "uint64": "u8", "float32": "f4", "float64": "f8",
          # legacy names
          "char": "i1", "unsigned_char": "u1", "short": "i2", "unsigned_short": "u2", "int": "i4",
          "unsigned_int": "u4", "long": "i8", "unsigned_long": "u8", "float": "f4", "double": "f8",
          "vtktypeint64": "i8", "vtktypeint32": "i4", "vtkidtype": "i8"}
_LEGACY = re.compile(rb"#\s*vtk DataFile Version\s+(\d+)\.(\d+)", re.IGNORECASE)


def is_polydata(head: bytes) -> bool:
    """An XML ``VTKFile`` of type ``PolyData``, or a legacy file with ``DATASET POLYDATA``."""
    if re.search(rb"<VTKFile[^>]*type=[\"']PolyData[\"']", head):
        return True
    return _LEGACY.match(head.lstrip()) is not None and re.search(rb"DATASET\s+POLYDATA", head, re.IGNORECASE) \
        is not None


def _header_type(root) -> str:
    """The XML file's ``header_type``, lower case; an absent or empty one is VTK's UInt32."""
    return (root.get("header_type") or "UInt32").lower()


def _corrupt(where: str, what: str) -> FormatError:
    return FormatError(where, what, "the file is corrupt or not VTK PolyData; export it again")


def strip_triangles(strip: np.ndarray) -> np.ndarray:
    """The ``(k - 2, 3)`` triangles of a strip of ``k`` vertex indices, every second reversed."""
    if len(strip) < 3:
        return np.zeros((0, 3), dtype=np.int64)
    tri = np.stack([strip[:-2], strip[1:-1], strip[2:]], axis=1)
    tri[1::2, :2] = tri[1::2, 1::-1]
    return tri


def _cells(connectivity: np.ndarray, offsets: np.ndarray, strips: bool, where: str) -> np.ndarray:
    """Triangles of cells given by ``connectivity`` and end ``offsets`` (polygons or strips)."""
    ends = _index_array(offsets, where, "cell offsets")
    connectivity = _index_array(connectivity, where, "cell connectivity")
    starts = np.concatenate([[0], ends[:-1]])
    if len(ends) and (np.any(ends < starts) or ends[-1] > len(connectivity)):
        raise _corrupt(where, "cell offsets are not increasing within the connectivity")
    if not strips:
        return _fans(connectivity, starts, ends - starts)
    pieces = []
    for start, end in zip(starts.tolist(), ends.tolist()):
        cell = connectivity[start:end]
        pieces.append(strip_triangles(cell))
    return np.concatenate(pieces) if pieces else np.zeros((0, 3), dtype=np.int64)


def _index_array(values: np.ndarray, where: str, what: str) -> np.ndarray:
    """``values`` as int64 when every one is a whole number in 0..2^62 (a file may store its
    indices in a float array: ``1e20`` or ``nan`` there is no index)."""
    if values.dtype.kind == "f":
        bad = ~np.isfinite(values) | (values != np.floor(values)) | (values < 0) | (values >= 2.0 ** 62)
    elif values.dtype.kind == "u":
        bad = values >= np.uint64(1 << 62)
    else:
        bad = values < 0
    if bad.any():
        raise _corrupt(where, f"the {what} hold {values[bad][0].item()!r}, which is no index")
    return values.astype(np.int64)


def _fans(connectivity: np.ndarray, starts: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Polygons as fans from their first vertex, all at once: polygon ``p`` of ``k`` vertices
    gives triangles ``(c[s], c[s+j], c[s+j+1])`` for ``j = 1..k-2`` (cells of fewer than 3
    vertices give none)."""
    count = np.maximum(sizes - 2, 0)
    owner = np.repeat(np.arange(len(sizes)), count)
    # j counts 1..k-2 within each polygon: the running index minus the polygon's first one.
    j = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count) + 1
    first = starts[owner]
    return np.stack([connectivity[first], connectivity[first + j], connectivity[first + j + 1]], axis=1)


def _mesh(where: str, fmt: str, points: np.ndarray, triangles: list[np.ndarray], skipped: int) -> MeshSource:
    faces = np.concatenate(triangles) if triangles else np.zeros((0, 3), dtype=np.int64)
    if not len(faces):
        raise InputError(where, "no faces (no polygons or triangle strips)", "export the surface with its faces")
    if faces.min() < 0 or faces.max() >= len(points):
        raise _corrupt(where, f"a cell refers to a point outside 0..{len(points) - 1}")
    dtype = "float32" if points.dtype == np.float32 else "float64"
    if points.dtype not in (np.float32, np.float64):
        points = points.astype(np.float64)
    left_out = CodedWarning(f"{skipped} vertex or line cells hold no volume and are left out", "reader")
    notes = (left_out,) if skipped else ()
    return indexed_source(fmt, np.ascontiguousarray(points), faces.astype(np.intp), dtype, notes)


# --- XML -------------------------------------------------------------------------------------


class _Xml:
    """Decodes the DataArrays of one XML VTKFile."""

    def __init__(self, where: str, root, appended: bytes, appended_base64: bool) -> None:
        self.where = where
        self.order = "<" if root.get("byte_order", "LittleEndian") == "LittleEndian" else ">"
        self.header = np.dtype(self.order + _TYPES[_header_type(root)])   # checked by _load_xml
        compressor = root.get("compressor")
        if compressor not in (None, "", "vtkZLibDataCompressor"):
            raise FormatError(where, f"its data are compressed by {compressor}, which p3d does not decode",
                              "write the file uncompressed or with zlib")
        self.compressed = bool(compressor)
        self.inflated = 0
        self.appended = appended
        self.appended_base64 = appended_base64

    def _blocks(self, data: bytes, header: np.ndarray) -> bytes:
        """The blocks of one compressed array, each inflated to exactly the size the header
        declares for it, and all arrays together to at most ``MAX_INFLATED`` bytes."""
        count = int(header[0])
        block, last = (int(header[1]), int(header[2])) if len(header) >= 3 else (0, 0)
        if count > len(header) - 3:
            raise _corrupt(self.where, f"a compressed array declares {count} blocks, but its header ends after "
                           f"{max(len(header) - 3, 0)}")
        sizes = header[3:3 + count].astype(np.int64)
        if len(sizes) and sizes.min() < 0:
            raise _corrupt(self.where, "a compressed block's size is negative")
        declared = (count - 1) * block + (last or block) if count else 0
        self.inflated += declared
        check_declared(self.where, self.inflated, "its compressed data")
        out, at = [], 0
        for k, size in enumerate(sizes.tolist()):
            expected = (last or block) if k == count - 1 else block
            out.append(inflate(self.where, data[at:at + size], expected, f"zlib block {k} of a DataArray"))
            at += size
        return b"".join(out)

    def _binary(self, data: bytes) -> bytes:
        """One array's bytes after its header: ``data`` is raw (appended raw) or decoded base64."""
        size = self.header.itemsize
        count = int(np.frombuffer(data[:size], self.header)[0])
        if not self.compressed:
            if size + count > len(data):
                raise _corrupt(self.where, f"a DataArray declares {count} bytes, but the file holds {len(data) - size}")
            return data[size:size + count]
        header = np.frombuffer(data[:size * (3 + count)], self.header)
        return self._blocks(data[size * (3 + count):], header)

    def _base64(self, text: bytes) -> bytes:
        """One array's bytes from base64 text, whose header may be encoded apart from the data
        (always so when compressed; either way when not). Decoding stops at padding, so a
        header encoded apart decodes alone."""
        text = b"".join(text.split())
        size = self.header.itemsize
        if not self.compressed:
            joined = base64.b64decode(text)
            count = int(np.frombuffer(joined[:size], self.header)[0])
            if len(joined) >= size + count:
                return joined[size:size + count]
            return base64.b64decode(text[_b64_len(size):])[:count]
        blocks = int(np.frombuffer(base64.b64decode(text[:_b64_len(size)])[:size], self.header)[0])
        head_len = _b64_len(size * (3 + blocks))
        header = np.frombuffer(base64.b64decode(text[:head_len])[:size * (3 + blocks)], self.header)
        return self._blocks(base64.b64decode(text[head_len:]), header)

    def array(self, node) -> np.ndarray:
        kind = _TYPES.get((node.get("type") or "").lower())
        if kind is None:
            raise _corrupt(self.where, f"a DataArray of unknown type {node.get('type')!r}")
        dtype = np.dtype(self.order + kind)
        fmt = (node.get("format") or "ascii").lower()
        try:
            if fmt == "ascii":
                # Decimal text is read at float64 whatever type the writer names.
                return np.array((node.text or "").split(), dtype=np.float64 if dtype.kind == "f" else np.int64)
            if fmt == "binary":
                data = self._base64((node.text or "").encode("ascii"))
            elif fmt == "appended":
                at = int(node.get("offset", "0"))
                if self.appended_base64:
                    data = self._base64(self.appended[at:])
                else:
                    data = self._binary(self.appended[at:])
            else:
                raise _corrupt(self.where, f"a DataArray of unknown format {fmt!r}")
            usable = len(data) - len(data) % dtype.itemsize
            return np.frombuffer(data[:usable], dtype).astype(dtype.newbyteorder("="))
        except FormatError:
            raise  # our own, a ValueError too: as it is
        except (ValueError, OverflowError, binascii.Error, IndexError) as exc:
            raise _corrupt(self.where, f"a DataArray cannot be decoded ({exc})") from None


def _b64_len(n: int) -> int:
    return 4 * ((n + 2) // 3)


def _split_appended(data: bytes) -> tuple[bytes, bytes, bool]:
    """The XML without its appended data (raw bytes are not XML), the appended bytes after the
    ``_`` marker, and whether they are base64."""
    start = data.find(b"<AppendedData")
    if start < 0:
        return data, b"", False
    tag_end = data.find(b">", start)
    marker = data.find(b"_", tag_end)
    stop = data.rfind(b"</AppendedData>")
    if tag_end < 0 or marker < 0 or stop < marker:
        raise ValueError("an unterminated AppendedData section")
    base64_data = b'encoding="base64"' in data[start:tag_end]
    return data[:tag_end + 1] + data[stop:], data[marker + 1:stop], base64_data


def _find(node, name: str):
    return [child for child in node.iter() if child.tag.rsplit("}", 1)[-1] == name]


def _load_xml(raw: RawInput) -> MeshSource:
    try:
        text, appended, is_base64 = _split_appended(raw.read_all())
        root = ElementTree.fromstring(text)
    except (ValueError, ElementTree.ParseError) as exc:
        raise _corrupt(raw.where, f"is not valid VTK XML ({exc})") from None
    if root.get("type") != "PolyData":
        raise _corrupt(raw.where, f"is a VTK {root.get('type')!r} file, not PolyData")
    if _header_type(root) not in ("uint32", "uint64"):
        raise _corrupt(raw.where, f"header_type {root.get('header_type')!r} is not UInt32 or UInt64")
    reader = _Xml(raw.where, root, appended, is_base64)
    points, triangles, skipped, base = [], [], 0, 0
    for piece in _find(root, "Piece"):
        arrays = _find(piece.find("Points") if piece.find("Points") is not None else piece, "DataArray")
        if not arrays:
            raise _corrupt(raw.where, "a Piece has no Points")
        xyz = reader.array(arrays[0])
        if len(xyz) % 3:
            raise _corrupt(raw.where, "the Points array is not a whole number of x, y, z triples")
        for section, strips in (("Polys", False), ("Strips", True), ("Verts", None), ("Lines", None)):
            node = piece.find(section)
            if node is None:
                continue
            named = {a.get("Name"): a for a in _find(node, "DataArray")}
            if "connectivity" not in named or "offsets" not in named:
                raise _corrupt(raw.where, f"{section} lacks its connectivity or offsets")
            offsets = reader.array(named["offsets"])
            if strips is None:
                skipped += len(offsets)
                continue
            triangles.append(_cells(reader.array(named["connectivity"]), offsets, strips, raw.where) + base)
        points.append(xyz.reshape(-1, 3))
        base += len(points[-1])
    if not points:
        raise _corrupt(raw.where, "no Piece")
    return _mesh(raw.where, "vtp", np.concatenate(points), triangles, skipped)


# --- legacy ----------------------------------------------------------------------------------


class _Legacy:
    """A cursor over a legacy VTK file: keyword lines, then ASCII numbers or big-endian binary."""

    def __init__(self, where: str, data: bytes) -> None:
        self.where, self.data, self.at = where, data, 0
        self.binary = False

    def line(self) -> bytes:
        while self.at < len(self.data):
            end = self.data.find(b"\n", self.at)
            end = len(self.data) if end < 0 else end
            text, self.at = self.data[self.at:end].strip(), end + 1
            if text:
                return text
        return b""

    def keyword_line(self) -> bytes:
        """The next line that is not blank and not in a METADATA block (which VTK 9 writes
        after any array with information keys, ended by a blank line)."""
        while True:
            text = self.line()
            if text.split()[:1] != [b"METADATA"]:
                return text
            self.skip_block()

    def skip_block(self) -> None:
        """Move past the lines up to the next blank line (or the end)."""
        while self.at < len(self.data):
            end = self.data.find(b"\n", self.at)
            end = len(self.data) if end < 0 else end
            text, self.at = self.data[self.at:end].strip(), end + 1
            if not text:
                return

    def numbers(self, count: int, kind: str) -> np.ndarray:
        dtype = np.dtype(">" + _TYPES[kind])
        if self.binary:
            stop = self.at + count * dtype.itemsize
            if stop > len(self.data):
                raise _corrupt(self.where, "the binary data end early")
            out = np.frombuffer(self.data[self.at:stop], dtype).astype(dtype.newbyteorder("="))
            self.at = stop
            return out
        found: list[bytes] = []
        while len(found) < count:
            text = self.line()
            if not text:
                raise _corrupt(self.where, f"expected {count} numbers, the file ends after {len(found)}")
            found += text.split()
        if len(found) != count:
            raise _corrupt(self.where, f"expected {count} numbers, found {len(found)} before the next keyword")
        try:
            # Decimal text is read at float64 whatever type the writer names.
            return np.array(found, dtype=np.float64 if dtype.kind == "f" else np.int64)
        except (ValueError, OverflowError):
            raise _corrupt(self.where, "a number cannot be read") from None


def _legacy_cells(cursor: _Legacy, words: list[bytes], version: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """A cell section's connectivity and end offsets, in the classic or the 5.1 layout."""
    first, second = _count(cursor, words[1]), _count(cursor, words[2])
    if version >= (5, 1):
        label = cursor.keyword_line().split()
        offsets = cursor.numbers(first, label[1].decode().lower() if len(label) > 1 else "vtktypeint64")
        label = cursor.keyword_line().split()
        connectivity = cursor.numbers(second, label[1].decode().lower() if len(label) > 1 else "vtktypeint64")
        return connectivity, offsets[1:]
    flat = _index_array(cursor.numbers(second, "int"), cursor.where, "cell sizes and indices")
    # The classic layout: each cell is its size k, then k indices. All cells of one size (the
    # common case) are checked at once; otherwise each size is read in turn, every step moving
    # on by k + 1 >= 1 values, so the walk ends within the list whatever the sizes say.
    if first and len(flat) % first == 0:
        k = len(flat) // first - 1
        table = flat.reshape(first, k + 1)
        if k >= 0 and (table[:, 0] == k).all():
            return table[:, 1:].ravel(), np.arange(1, first + 1, dtype=np.int64) * k
    keep = np.ones(len(flat), dtype=bool)
    ends: list[int] = []
    at = 0
    sizes = flat.tolist()
    for _ in range(first):
        if at >= len(sizes):
            raise _corrupt(cursor.where, "a cell list is shorter than its count says")
        keep[at] = False
        at += sizes[at] + 1
        ends.append(at - len(ends) - 1)
    if at != len(sizes):
        raise _corrupt(cursor.where, f"the cells' sizes add up to {at} values, but the section declares {len(sizes)}")
    return flat[keep], np.array(ends, dtype=np.int64)


def _count(cursor: _Legacy, word: bytes) -> int:
    """A declared count: a non-negative integer no larger than the file could hold."""
    try:
        value = int(word)
    except ValueError:
        raise _corrupt(cursor.where, f"the count {word[:30].decode(errors='replace')!r} is not an integer") from None
    if not 0 <= value <= len(cursor.data):
        raise _corrupt(cursor.where, f"the count {value} is negative or larger than the file could hold")
    return value


_SECTIONS = {b"POLYGONS": False, b"TRIANGLE_STRIPS": True, b"VERTICES": None, b"LINES": None}
_DATA = (b"POINT_DATA", b"CELL_DATA", b"FIELD")


def _load_legacy(raw: RawInput) -> MeshSource:
    cursor = _Legacy(raw.where, raw.read_all())
    found = _LEGACY.match(cursor.line())
    if found is None:
        raise _corrupt(raw.where, "has no '# vtk DataFile Version' line")
    version = (int(found.group(1)), int(found.group(2)))
    cursor.line()  # the title
    mode = cursor.line().upper()
    if mode not in (b"ASCII", b"BINARY"):
        raise _corrupt(raw.where, f"the third line is {mode[:20]!r}, not ASCII or BINARY")
    cursor.binary = mode == b"BINARY"
    dataset = cursor.line().split()
    if len(dataset) != 2 or dataset[1].upper() != b"POLYDATA":
        raise _corrupt(raw.where, "is not a POLYDATA dataset")
    points, triangles, skipped = None, [], 0
    while True:
        words = cursor.keyword_line().split()
        if not words or words[0].upper() in _DATA:
            break
        key = words[0].upper()
        try:
            if key == b"POINTS":
                points = cursor.numbers(3 * _count(cursor, words[1]), words[2].decode().lower()).reshape(-1, 3)
            elif key in _SECTIONS and len(words) >= 3:
                connectivity, offsets = _legacy_cells(cursor, words, version)
                if _SECTIONS[key] is None:
                    skipped += len(offsets)
                else:
                    triangles.append(_cells(connectivity, offsets, bool(_SECTIONS[key]), raw.where))
            else:
                raise _corrupt(raw.where, f"unexpected section {key[:30].decode(errors='replace')!r}")
        except FormatError:
            raise  # our own, a ValueError too: as it is
        except (ValueError, OverflowError, IndexError, KeyError) as exc:
            raise _corrupt(raw.where, f"a {key[:30].decode(errors='replace')} section cannot be read ({exc})") from None
    if points is None:
        raise _corrupt(raw.where, "has no POINTS")
    return _mesh(raw.where, "vtk-polydata", points, triangles, skipped)


def load(raw: RawInput) -> MeshSource:
    """Read VTK PolyData, XML or legacy (see the module's description).

    Raises
    ------
    FormatError
        Corrupt, not PolyData, or compressed by something other than zlib.
    InputError
        No polygons or strips.
    """
    head = raw.head(512)
    if _LEGACY.match(head.lstrip()):
        return _load_legacy(raw)
    return _load_xml(raw)
