"""Axis-aligned bounds of triangles, projected through a linear map: exact, streamed.

Every class is exact: the polyhedral shapes and meshes by projecting their vertices (the
box around a convex hull is attained at vertices, the Physics3D note's eq. 10), the round shapes by
their closed forms (``p3d_cli.shapes``). A mesh is projected as it is: no convex hull is
built, because projecting all corners is one linear pass, already cheaper than any hull
algorithm's O(n log n) pass over the same vertices. Measured on a 1.3M-triangle sphere: 0.08 s
to project every corner, against 8 s to merge vertices and 22 s for scipy's ConvexHull
(docs/shapes.md). A hull would pay off only when one mesh is bounded under many rotations,
which one ``p3d bounds`` run never does.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from p3d_cli.results import Bounds

#: Triangles projected at a time when one big array is given.
_BLOCK = 1 << 16


def projected_bounds(points: np.ndarray, rotation=None, translation=None) -> Bounds:
    """Axis-aligned box of ``R p + t`` over the points.

    Parameters
    ----------
    points : (k, 3) float64
    rotation : (3, 3) array_like, optional
        Default the identity.
    translation : (3,) array_like, optional
        Default zero.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if rotation is None:
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    else:
        # One contiguous projection per world axis, reduced at once: about 3-5 times faster
        # than ``pts @ R.T`` followed by strided column reductions on an (n, 3) array.
        r = np.asarray(rotation, dtype=np.float64)
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        lo, hi = np.empty(3), np.empty(3)
        for i in range(3):
            proj = x * r[i, 0]
            proj += y * r[i, 1]
            proj += z * r[i, 2]
            lo[i], hi[i] = proj.min(), proj.max()
    if translation is not None:
        t = np.asarray(translation, dtype=np.float64).reshape(3)
        lo, hi = lo + t, hi + t
    return Bounds(lo, hi)


def triangles_bounds(blocks: np.ndarray | Iterable[np.ndarray], scale=None, rotation=None,
                     translation=None) -> Bounds:
    """Exact bounds of ``R (S p) + t`` over every corner of the triangles.

    Parameters
    ----------
    blocks : (n, 3, 3) array, or an iterable of such blocks (float32 or float64)
        A streamed mesh is never held whole: each block is projected and dropped.
    scale : (3,) array_like, optional
        Already checked (``p3d_cli.geometry.placement.check_scale``).
    rotation : (3, 3) array_like, optional
    translation : (3,) array_like, optional
    """
    if isinstance(blocks, np.ndarray):
        # Blocks that fit in cache project several times faster than one huge array.
        array = blocks
        blocks = (array[i:i + _BLOCK] for i in range(0, max(len(array), 1), _BLOCK))
    m = np.eye(3) if scale is None else np.diag(np.asarray(scale, dtype=np.float64).reshape(3))
    if rotation is not None:
        m = np.asarray(rotation, dtype=np.float64) @ m
    lo = hi = None
    for block in blocks:
        if len(block) == 0:
            continue
        b = projected_bounds(np.asarray(block, dtype=np.float64).reshape(-1, 3), m)
        lo = b.min if lo is None else np.minimum(lo, b.min)
        hi = b.max if hi is None else np.maximum(hi, b.max)
    if lo is None:
        raise ValueError("no triangles to bound")
    if translation is not None:
        t = np.asarray(translation, dtype=np.float64).reshape(3)
        with np.errstate(over="ignore"):        # an overflow is refused by checked_bounds
            lo, hi = lo + t, hi + t
    return Bounds(lo, hi)


def checked_bounds(where: str, bounds: Bounds) -> Bounds:
    """``bounds``, or ``RangeError`` when a corner or the size is beyond float64 (a part placed
    or scaled past 1.8e308): an infinite bound would be a silently wrong number.

    Raises
    ------
    RangeError
    """
    with np.errstate(over="ignore", invalid="ignore"):
        finite = np.isfinite(bounds.min).all() and np.isfinite(bounds.max).all() and np.isfinite(bounds.size).all()
    if not finite:
        from p3d_cli.errors import RangeError

        raise RangeError(where, "the placed bounds overflow float64 (a corner or the size is beyond 1.8e308)",
                         "measure in a larger unit (e.g. km instead of mm), or nearer the origin")
    return bounds
