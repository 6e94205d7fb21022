"""Coordinates as the mesh sums read them: float64 columns, about a local origin.

The integrals (``p3d_cli.mesh.integrals``), the closedness and boundary keys and the volume
check all take triangles ``(n, 3, 3)`` as ``(3, 3, n)`` columns (vertex slot, axis, triangle),
widened to float64 first, and shift them to an origin inside the part's bounding box, so that
the terms have the part's size rather than its distance from the world origin (docs/method.md,
"Precision far from the origin" and "Float32 input").
"""

from __future__ import annotations

import numpy as np


def columns(points: np.ndarray) -> np.ndarray:
    """A fresh float64 copy of ``points`` ``(n, k, 3)`` as ``(k, 3, n)``: vertex slot, axis, element.

    Float32 input is widened (exactly) first (docs/method.md, "Float32 input": widen before any arithmetic). Always a
    new array, so callers may shift it in place.
    """
    points = np.asarray(points)
    out = np.empty((points.shape[1], 3, points.shape[0]))
    np.copyto(out, points.transpose(1, 2, 0))
    return out


def local_origin(points: np.ndarray) -> np.ndarray:
    """A local origin near the part: the centre of the points' bounding box.

    For float32 input the centre is rounded to float32, so that ``p - origin`` is exact in
    float64 for every float32 coordinate ``p`` of comparable magnitude.
    """
    flat = np.asarray(points).reshape(-1, 3)
    if flat.shape[0] == 0:
        return np.zeros(3)
    return origin_from_bounds(flat.min(axis=0), flat.max(axis=0), flat.dtype == np.float32)


def origin_from_bounds(lo: np.ndarray, hi: np.ndarray, float32: bool) -> np.ndarray:
    """``local_origin`` from the points' bounds (for callers that have them already)."""
    center = 0.5 * (np.asarray(lo, dtype=np.float64) + np.asarray(hi, dtype=np.float64))
    if float32:
        center = center.astype(np.float32).astype(np.float64)
    return center
