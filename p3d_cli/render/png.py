"""PNG files from RGB(A) arrays and back, with the standard library's zlib (no imaging library).

The encoder writes 8-bit truecolour (RGB or RGBA), one IDAT chunk, every row with the "Up"
filter (each byte minus the byte above it, modulo 256): shaded surfaces change little from one
row to the next, so the filtered rows are mostly small numbers that deflate well, and the
filter is one numpy subtraction over the whole image. The reader decodes any 8-bit RGB, RGBA,
grey or grey-alpha PNG without interlacing (all five row filters), which covers what this
module and common tools write; it is what the tests read pictures back with.

Format: ISO/IEC 15948 (PNG), chunk layout and filters as in its sections 5 and 9.
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

SIGNATURE = b"\x89PNG\r\n\x1a\n"
_COLOUR_TYPES = {1: 0, 2: 4, 3: 2, 4: 6}     # channels -> PNG colour type
_CHANNELS = {v: k for k, v in _COLOUR_TYPES.items()}


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def encode_png(pixels: np.ndarray, level: int = 6, text: dict[str, str] | None = None) -> bytes:
    """The bytes of a PNG file holding ``pixels``.

    Parameters
    ----------
    pixels : (h, w, 3) or (h, w, 4) uint8
        RGB or RGBA, rows from the top.
    level : int
        zlib compression level (0-9).
    text : dict, optional
        ``tEXt`` entries (Latin-1 keys and values), e.g. ``{"Software": "p3d"}``.

    Raises
    ------
    ValueError
        Not an (h, w, 3|4) uint8 array, or an empty one.
    """
    pixels = np.asarray(pixels)
    if pixels.dtype != np.uint8 or pixels.ndim != 3 or pixels.shape[2] not in (3, 4) or 0 in pixels.shape:
        raise ValueError(f"expected an (h, w, 3|4) uint8 array, got {pixels.shape} {pixels.dtype}")
    height, width, channels = pixels.shape
    rows = pixels.reshape(height, width * channels)
    filtered = np.empty((height, width * channels + 1), dtype=np.uint8)
    filtered[:, 0] = 2                                   # filter type 2: Up
    filtered[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=filtered[1:, 1:])   # uint8 arithmetic wraps modulo 256
    header = struct.pack(">IIBBBBB", width, height, 8, _COLOUR_TYPES[channels], 0, 0, 0)
    out = [SIGNATURE, _chunk(b"IHDR", header)]
    for key, value in (text or {}).items():
        out.append(_chunk(b"tEXt", key.encode("latin-1") + b"\0" + value.encode("latin-1", "replace")))
    out.append(_chunk(b"IDAT", zlib.compress(filtered.tobytes(), level)))
    out.append(_chunk(b"IEND", b""))
    return b"".join(out)


def decode_png(data: bytes) -> np.ndarray:
    """The pixels of a PNG file: ``(h, w, channels)`` uint8 (channels 1-4 as stored).

    Raises
    ------
    ValueError
        Not a PNG, or a kind this reader does not decode (palette, 16-bit, interlaced).
    """
    if not data.startswith(SIGNATURE):
        raise ValueError("not a PNG file (no PNG signature)")
    pos, header, compressed = len(SIGNATURE), None, []
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if len(body) != length:
            raise ValueError("truncated PNG chunk")
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            compressed.append(body)
        elif kind == b"IEND":
            break
        pos += 12 + length
    if header is None:
        raise ValueError("PNG without IHDR")
    width, height, depth, colour, _, _, interlace = header
    if depth != 8 or colour not in _CHANNELS or interlace:
        raise ValueError(f"unsupported PNG (bit depth {depth}, colour type {colour}, interlace {interlace})")
    channels = _CHANNELS[colour]
    stride = width * channels
    raw = np.frombuffer(zlib.decompress(b"".join(compressed)), dtype=np.uint8)
    if raw.size != height * (stride + 1):
        raise ValueError("PNG image data has the wrong size")
    raw = raw.reshape(height, stride + 1)
    out = np.zeros((height, stride), dtype=np.uint8)
    above = np.zeros(stride, dtype=np.int32)
    for r in range(height):
        kind, line = int(raw[r, 0]), raw[r, 1:].astype(np.int32)
        if kind == 0:
            row = line
        elif kind == 2:
            row = (line + above) & 0xFF
        elif kind in (1, 3, 4):
            row = _sequential(kind, line, above, channels)
        else:
            raise ValueError(f"unknown PNG row filter {kind}")
        out[r] = row
        above = row
    return out.reshape(height, width, channels)


def _sequential(kind: int, line: np.ndarray, above: np.ndarray, bpp: int) -> np.ndarray:
    """Undo the Sub (1), Average (3) or Paeth (4) filter, which depend on the decoded left byte."""
    row = np.zeros_like(line)
    for i in range(line.size):
        left = row[i - bpp] if i >= bpp else 0
        up = above[i]
        if kind == 1:
            guess = left
        elif kind == 3:
            guess = (left + up) >> 1
        else:
            corner = above[i - bpp] if i >= bpp else 0
            p = left + up - corner
            pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
            guess = left if pa <= pb and pa <= pc else (up if pb <= pc else corner)
        row[i] = (line[i] + guess) & 0xFF
    return row
