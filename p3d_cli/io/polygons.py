"""Polygons and triangle strips to triangles: the one place every reader splits faces.

Polygons are split as fans from their first vertex (``v0, vi, vi+1``), the convention the
reference values of the test meshes were computed with; strips alternate their winding so
that every triangle keeps the strip's orientation.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fan_triangles", "strip_triangles"]


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
    (sum(sizes - 2), 3) int32 or int64
        Triangles ``(v0, vi, vi+1)`` for ``i = 1 .. k-2`` of each polygon, in order: int32
        when ``corners`` is int32 (half the memory of a large mesh's faces), else int64.
    """
    corners = np.asarray(corners)
    if corners.dtype != np.int32:
        corners = corners.astype(np.int64, copy=False)
    sizes = np.asarray(sizes, dtype=np.int64)
    if len(sizes) == 0:
        return np.zeros((0, 3), dtype=corners.dtype)
    k = int(sizes[0])
    if (sizes == k).all():
        # All polygons the same size (the common case: all triangles or all quads).
        polygons = corners.reshape(len(sizes), k)
        if k == 3:
            return polygons
        tris = np.empty((len(sizes), k - 2, 3), dtype=corners.dtype)
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


def strip_triangles(indices: np.ndarray) -> np.ndarray:
    """Triangles of triangle strips, as PLY's ``tristrips`` element stores them.

    Parameters
    ----------
    indices : (m,) integer
        Vertex indices of one or more strips, strips separated by ``-1`` (the Stanford
        range-image convention).

    Returns
    -------
    (t, 3) int64
        For a strip ``s``: ``(s[i], s[i+1], s[i+2])`` for even ``i`` and ``(s[i+1], s[i],
        s[i+2])`` for odd ``i``, so that every triangle has the winding of the first. Triangles
        with a repeated index (the zero-area joins strips use to turn corners) are dropped: they
        hold no area and no volume.
    """
    indices = np.asarray(indices, dtype=np.int64).ravel()
    if indices.size < 3:
        return np.zeros((0, 3), dtype=np.int64)
    a, b, c = indices[:-2], indices[1:-1], indices[2:]
    # Position of each index inside its strip (the strip starts after the last -1 before it):
    # the winding alternates with it.
    separator = indices < 0
    steps = np.arange(indices.size)
    begins = np.concatenate(([True], separator[:-1]))
    position = steps - np.maximum.accumulate(np.where(begins, steps, 0))
    keep = ~(separator[:-2] | separator[1:-1] | separator[2:])
    keep &= (a != b) & (b != c) & (a != c)
    odd = (position[:-2] % 2) == 1
    first = np.where(odd, b, a)
    second = np.where(odd, a, b)
    return np.stack([first, second, c], axis=1)[keep]
