"""STL, binary and ASCII.

Binary STL: an 80-byte header, a little-endian uint32 triangle count ``n``, then ``n`` records
of 50 bytes (normal, three corners as float32, a uint16 attribute). The header may begin with
``solid`` (many CAD exporters write that), so binary and ASCII are told apart by the size:
a binary file holds ``84 + 50 n`` bytes (trailing bytes are tolerated with a warning), never by
the first word (trimesh 5.2 gets this wrong and returns an empty mesh). Binary files
are streamed in blocks, so memory stays far below the file's size.

ASCII STL (``p3d_cli.io.stl.ascii``): ``solid``/``endsolid`` blocks (several in one file are
read as one mesh) of ``facet normal``/``outer loop``/``vertex``×3/``endloop``/``endfacet``.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import BLOCK, MeshSource
from p3d_cli.warning_codes import CodedWarning

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
        from p3d_cli.io.stl.ascii import load_ascii  # a binary STL's run does not import it

        return load_ascii(raw)
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
    warning = CodedWarning(f"{extra} trailing bytes after the last of {n} triangles were ignored", "trailing-data")
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
