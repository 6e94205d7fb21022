"""The exact winding number of a point with respect to a closed triangle surface.

A ray leaves the point along +x. Each face it passes through changes the winding number by
the sign of the x component of the face's normal (a face whose normal points the way the
ray goes is one the ray leaves the solid through); summed, they give the winding number:
1 inside an outward-wound closed surface, -1 inside an inward-wound one, 0 outside.

Every sign is exact (``p3d_cli.geometry.predicates``). A ray through an edge or a vertex is
resolved by simulation of simplicity (Edelsbrunner and Mücke, *ACM Trans. Graphics* 9(1),
1990): the point is moved by ``(0, ε, ε²)``, which lies on no edge line, so each edge is
passed on one side, the same for its two faces. A point exactly on the surface has no winding
number and is reported as such (``None``): it lies in the plane of a face whose box holds it,
and inside that face's triangle (closed), decided exactly too.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.predicates import Planes, orient2d

#: Faces per vectorised step.
_STEP = 1 << 16


def _perturbed_sides(a: np.ndarray, b: np.ndarray, p: np.ndarray, safe: bool) -> np.ndarray:
    """Signs of ``orient2d(a, b, p + (ε, ε²))`` in the (y, z) plane: exact, never zero for a
    proper edge (the first nonzero of the sign, of ``a_z - b_z`` and of ``b_y - a_y``)."""
    side = orient2d(a, b, np.broadcast_to(p, a.shape), safe)
    tie = side == 0
    if tie.any():
        dz = np.sign(a[tie, 1] - b[tie, 1]).astype(np.int8)
        dy = np.sign(b[tie, 0] - a[tie, 0]).astype(np.int8)
        side[tie] = np.where(dz != 0, dz, dy)
    return side


def winding_number(point: np.ndarray, triangles_of, safe: bool = True) -> int | None:
    """The winding number of ``point`` with respect to the faces ``triangles_of()`` yields.

    Parameters
    ----------
    point : (3,) float64
    triangles_of : callable
        Returns an iterator over ``(k, 3, 3)`` float64 blocks of the closed surface's faces.
    safe : bool
        Whether all coordinates lie in the filter's safe range.

    Returns
    -------
    int or None
        None when the point lies on the surface.
    """
    point = np.asarray(point, dtype=np.float64)
    p2 = point[1:][None, :]
    total = 0
    for tri in triangles_of():
        if _on_a_face(point, tri, safe):
            return None
        # Faces the ray can meet: their y and z ranges hold the point's (a face passed only
        # at its rim is decided by the perturbed sides below, which never count it twice).
        y, z = tri[:, :, 1], tri[:, :, 2]
        near = ((y.min(axis=1) <= point[1]) & (y.max(axis=1) >= point[1])
                & (z.min(axis=1) <= point[2]) & (z.max(axis=1) >= point[2]))
        tri = tri[near]
        if len(tri) == 0:
            continue
        a, b, c = (np.ascontiguousarray(tri[:, k, 1:]) for k in range(3))
        facing = orient2d(a, b, c, safe)                      # sign of the normal's x component
        rows = np.flatnonzero(facing != 0)
        if rows.size == 0:
            continue
        a, b, c, facing, tri = a[rows], b[rows], c[rows], facing[rows], tri[rows]
        inside = np.ones(rows.size, dtype=bool)
        for u, v in ((a, b), (b, c), (c, a)):
            inside &= _perturbed_sides(u, v, p2, safe) == facing
        rows = np.flatnonzero(inside)
        if rows.size == 0:
            continue
        tri, facing = tri[rows], facing[rows]
        level = Planes(tri[:, 0], tri[:, 1], tri[:, 2], safe).side(np.broadcast_to(point, (rows.size, 3)).copy())
        ahead = level != facing                               # the face is met at x > point's x
        total += int(facing[ahead].sum())
    return total


def _on_a_face(point: np.ndarray, tri: np.ndarray, safe: bool) -> bool:
    """Whether ``point`` lies on one of the triangles ``(k, 3, 3)`` (closed), exactly."""
    near = ((tri.min(axis=1) <= point) & (tri.max(axis=1) >= point)).all(axis=1)
    tri = tri[near]
    if len(tri) == 0:
        return False
    flat = Planes(tri[:, 0], tri[:, 1], tri[:, 2], safe).side(np.broadcast_to(point, (len(tri), 3)).copy()) == 0
    tri = tri[flat]
    for axis in range(3):           # a coordinate plane where the triangle is not a segment
        keep = [(axis + 1) % 3, (axis + 2) % 3]
        a, b, c = (np.ascontiguousarray(tri[:, k][:, keep]) for k in range(3))
        area = orient2d(a, b, c, safe)
        rows = area != 0
        if rows.any():
            p = np.broadcast_to(point[keep], (int(rows.sum()), 2))
            sides = [orient2d(u[rows], v[rows], p, safe) * area[rows] for u, v in ((a, b), (b, c), (c, a))]
            if ((sides[0] >= 0) & (sides[1] >= 0) & (sides[2] >= 0)).any():
                return True
        tri = tri[~rows]
        if len(tri) == 0:
            return False
    return False
