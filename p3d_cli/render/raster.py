"""A z-buffer for triangles in screen space: which face is nearest at each pixel, and how deep.

Pure numpy, no display and no GPU. Each triangle covers the pixel centres (``(i + 0.5, j + 0.5)``)
inside it, found row by row: on each row of centres its span runs between the two crossings of
the centre line with its edges; a centre on an edge counts as inside (no cracks between
neighbours; a centre on a shared edge goes to the nearer face). Depth is the triangle's plane
at the centre. The
nearest fragment per pixel is kept by one ``numpy.minimum.at`` over 64-bit keys that pack the
quantised depth above the face index, so depth ties are broken by the lower face index and the
result does not depend on the order of the work.

All triangles are done together, as array operations over their rows of pixels and then over
the pixels of those rows, in chunks of about ``CHUNK`` pixels: the work is the number of
covered pixels plus the number of rows, whatever the triangles' sizes (a million triangles of
a pixel each, or twelve that fill the picture).

Sorting faces back to front (the painter's algorithm, which matplotlib's 3D collections use)
is both slower and wrong where faces overlap cyclically or cross; a z-buffer is neither.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Pixels (or rows) handled per array operation (memory: ~60 bytes each).
CHUNK = 1 << 21
#: The key of a pixel no face covers.
EMPTY = np.uint64(np.iinfo(np.uint64).max)
_DEPTH_STEPS = float(2**32 - 2)


@dataclass(frozen=True)
class DepthBuffer:
    """What the z-buffer found.

    Attributes
    ----------
    face : (h, w) int64
        Index of the nearest face at each pixel, -1 where no face covers the pixel centre.
    depth : (h, w) float64
        Its depth (distance along the view direction; smaller is nearer), ``inf`` where empty.
    """

    face: np.ndarray
    depth: np.ndarray

    @property
    def covered(self) -> np.ndarray:
        """(h, w) bool: some face covers the pixel."""
        return self.face >= 0


def rasterize(x: np.ndarray, y: np.ndarray, z: np.ndarray, width: int, height: int) -> DepthBuffer:
    """The nearest face at each pixel centre.

    Parameters
    ----------
    x, y : (n, 3) float
        Corner positions in pixels: ``x`` to the right from the left edge, ``y`` down from the
        top edge (pixel ``(i, j)`` has its centre at ``(i + 0.5, j + 0.5)``).
    z : (n, 3) float
        Corner depths (smaller is nearer); finite.
    width, height : int

    Returns
    -------
    DepthBuffer
    """
    keys = np.full(width * height, EMPTY, dtype=np.uint64)
    if len(x) == 0:
        return _buffer(keys, width, height, 0.0, 1.0)
    # Corner-major copies (3, n): the per-face minima, maxima and differences below then run
    # over contiguous rows, several times faster than reductions along a short last axis.
    x = np.ascontiguousarray(np.asarray(x, dtype=np.float64).T)
    y = np.ascontiguousarray(np.asarray(y, dtype=np.float64).T)
    z = np.ascontiguousarray(np.asarray(z, dtype=np.float64).T)
    z_low, z_high = float(z.min()), float(z.max())
    span = z_high - z_low if z_high > z_low else 1.0
    # Rows of centres each triangle reaches: j + 0.5 in [min y, max y], within the picture.
    j0 = np.maximum(np.ceil(np.minimum(np.minimum(y[0], y[1]), y[2]) - 0.5), 0)
    j1 = np.minimum(np.floor(np.maximum(np.maximum(y[0], y[1]), y[2]) - 0.5), height - 1)
    x_low = np.minimum(np.minimum(x[0], x[1]), x[2])
    x_high = np.maximum(np.maximum(x[0], x[1]), x[2])
    area = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0])
    live = (j1 >= j0) & (x_high >= 0.5) & (x_low <= width - 0.5) & (area != 0) & np.isfinite(area)
    faces = np.flatnonzero(live)
    if faces.size == 0:
        return _buffer(keys, width, height, z_low, span)
    # The depth plane z = z0 + gx (px - x0) + gy (py - y0) of each face.
    e1x, e1y, e1z = x[1] - x[0], y[1] - y[0], z[1] - z[0]
    e2x, e2y, e2z = x[2] - x[0], y[2] - y[0], z[2] - z[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        gx = (e1z * e2y - e2z * e1y) / area
        gy = (e2z * e1x - e1z * e2x) / area
    levels = _DEPTH_STEPS / span
    counts = (j1[faces] - j0[faces] + 1).astype(np.int64)
    ends = np.cumsum(counts)
    start = 0
    while start < faces.size:
        # Whole faces per chunk of rows (one face's rows may make a chunk on their own).
        stop = max(int(np.searchsorted(ends, (ends[start - 1] if start else 0) + CHUNK, "right")), start + 1)
        chosen = faces[start:stop]
        rows_face = np.repeat(chosen, counts[start:stop])
        first = np.repeat(np.cumsum(counts[start:stop]) - counts[start:stop], counts[start:stop])
        row = j0[rows_face] + (np.arange(rows_face.size) - first)
        _rows(keys, rows_face, row, x, y, z, gx, gy, width, z_low, levels)
        start = stop
    return _buffer(keys, width, height, z_low, span)


def _rows(keys, face, row, x, y, z, gx, gy, width, z_low, levels) -> None:
    """Fill the pixels of the given rows of faces (``face``, ``row``: one entry per row)."""
    centre = row + 0.5
    left = np.full(face.size, np.inf)
    right = np.full(face.size, -np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        ya, yb = y[a, face], y[b, face]
        xa, xb = x[a, face], x[b, face]
        crosses = (np.minimum(ya, yb) <= centre) & (centre <= np.maximum(ya, yb)) & (ya != yb)
        with np.errstate(divide="ignore", invalid="ignore"):
            at = xa + (centre - ya) * (xb - xa) / (yb - ya)
        # Rounding may put a crossing a hair outside its edge's x range: clamp it back.
        at = np.clip(at, np.minimum(xa, xb), np.maximum(xa, xb))
        np.minimum(left, np.where(crosses, at, np.inf), out=left)
        np.maximum(right, np.where(crosses, at, -np.inf), out=right)
    i0 = np.maximum(np.ceil(left - 0.5), 0)
    i1 = np.minimum(np.floor(right - 0.5), width - 1)
    spans = np.where(i1 >= i0, i1 - i0 + 1, 0).astype(np.int64)
    total = int(spans.sum())
    if total == 0:
        return
    keep = spans > 0
    face, row, i0, spans, centre = face[keep], row[keep], i0[keep], spans[keep], centre[keep]
    ends = np.cumsum(spans)
    start = 0
    while start < face.size:        # chunks of about CHUNK pixels (whole rows)
        stop = max(int(np.searchsorted(ends, (ends[start - 1] if start else 0) + CHUNK, "right")), start + 1)
        part = slice(start, stop)
        _pixels(keys, face[part], row[part], i0[part], spans[part], centre[part], x, y, z, gx, gy, width,
                z_low, levels)
        start = stop


def _pixels(keys, face, row, i0, spans, centre, x, y, z, gx, gy, width, z_low, levels) -> None:
    """Depth-test the ``spans`` pixels from column ``i0`` of each row."""
    total = int(spans.sum())
    each = np.repeat(np.arange(face.size), spans)
    column = i0[each] + (np.arange(total) - np.repeat(np.cumsum(spans) - spans, spans))
    f = face[each]
    depth = z[0, f] + gx[f] * (column + 0.5 - x[0, f]) + gy[f] * (centre[each] - y[0, f])
    level = np.clip((depth - z_low) * levels, 0, _DEPTH_STEPS).astype(np.uint64)
    key = (level << np.uint64(32)) | f.astype(np.uint64)
    np.minimum.at(keys, row[each].astype(np.int64) * width + column.astype(np.int64), key)


def _buffer(keys: np.ndarray, width: int, height: int, z_low: float, span: float) -> DepthBuffer:
    empty = keys == EMPTY
    face = (keys & np.uint64(0xFFFFFFFF)).astype(np.int64)
    face[empty] = -1
    depth = (keys >> np.uint64(32)).astype(np.float64) / _DEPTH_STEPS * span + z_low
    depth[empty] = np.inf
    return DepthBuffer(face.reshape(height, width), depth.reshape(height, width))
