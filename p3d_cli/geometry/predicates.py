"""Exact orientation signs of float64 points: a float filter with a proven bound, then integers.

Every float64 is a dyadic rational, so the sign of a determinant of coordinate differences is
a well-defined exact quantity. It is decided in two stages (Shewchuk 1997, "Adaptive precision
floating-point arithmetic and fast robust geometric predicates", *Discrete Comput. Geom.* 18,
stage A of his ``orient2d`` and ``orient3d``):

1. **Filter.** The determinant is evaluated in float64 exactly as Shewchuk's stage A does it
   (three rounded differences from a common point, the 2 × 2 minors of two of them, their dot
   product with the third; for 2-D, two products and their difference). His error analysis
   bounds the rounding error by ``(7 + 56ε)ε · P`` in 3-D and ``(3 + 16ε)ε · P`` in 2-D, with
   ``ε = 2⁻⁵³`` and ``P`` the *permanent*: the same expression with every product replaced by
   its absolute value, evaluated in float64 too. When ``|det| > bound`` the float sign is the
   exact sign. When ``P == 0`` every product is exactly zero, so the determinant is exactly
   zero too: points on an axis-aligned plane (flat faces of CAD parts) are decided here.
2. **Exact.** The few others are computed with Python integers: each coordinate is its integer
   mantissa times ``2**e`` (``numpy.frexp``), shifted to the smallest exponent among the points
   of that test, so the determinant is an integer multiple of a power of two with the same sign.

The bound assumes no product under- or overflows. ``in_safe_range`` checks that every nonzero
coordinate lies in ``[2**-200, 2**200]``: then every difference is zero or in
``[2**-252, 2**201]`` and every triple product is a normal float64. Callers with points outside
that range pass ``safe=False`` and every test goes to the integers.

Conventions: ``orient3d(a, b, c, d)`` is the sign of ``((b - a) × (c - a)) · (d - a)``, positive
when ``d`` lies on the side the right-handed normal of ``(a, b, c)`` points to (the *opposite* of
Shewchuk's sign); ``orient2d(a, b, c)`` is the sign of ``(b - a) × (c - a)``, positive when
``a, b, c`` turn counter-clockwise (Shewchuk's).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

#: Half a unit in the last place of float64 (Shewchuk's ε).
EPS = 2.0 ** -53
#: Shewchuk's stage-A error bounds, as multiples of the permanent.
O3D_BOUND = (7.0 + 56.0 * EPS) * EPS
CCW_BOUND = (3.0 + 16.0 * EPS) * EPS
#: Nonzero coordinates within these magnitudes keep every product of the filters normal.
SAFE_LOW, SAFE_HIGH = 2.0 ** -200, 2.0 ** 200


def in_safe_range(points: np.ndarray) -> bool:
    """Whether every nonzero coordinate of ``points`` has its magnitude in ``[2**-200, 2**200]``."""
    magnitude = np.abs(np.asarray(points, dtype=np.float64))
    if magnitude.size == 0:
        return True
    if not float(magnitude.max()) <= SAFE_HIGH:          # also refuses NaN
        return False
    nonzero = magnitude[magnitude != 0]
    return nonzero.size == 0 or float(nonzero.min()) >= SAFE_LOW


class Planes:
    """The oriented planes of ``k`` triangles ``(a, b, c)``, for exact side tests of points.

    The minors of ``b - a`` and ``c - a`` (the normal, as Shewchuk's stage A rounds it) and their
    permanents are computed once, so each ``side`` query costs one rounded difference and two
    dot products.

    Parameters
    ----------
    a, b, c : (k, 3) float64
    safe : bool
        Whether the points lie in the filter's safe range (``in_safe_range``); if not, every
        query is decided by the exact stage.
    """

    def __init__(self, a: np.ndarray, b: np.ndarray, c: np.ndarray, safe: bool = True):
        self.a, self.b, self.c, self.safe = a, b, c, safe
        if not safe:        # products may overflow or underflow: only the integer stage counts,
            # and the rounded normal only hints at a projection: computed on a scaled copy.
            scale = np.max(np.abs(np.stack([a, b, c])), axis=(0, 2), keepdims=False)
            scale = np.where(scale > 0, scale, 1.0)[:, None]
            a, b, c = (np.ldexp(p, -np.frexp(scale)[1]) for p in (a, b, c))
        ux, uy, uz = (b[:, i] - a[:, i] for i in range(3))
        vx, vy, vz = (c[:, i] - a[:, i] for i in range(3))
        p = (uy * vz, uz * vy, uz * vx, ux * vz, ux * vy, uy * vx)
        self.normal = (p[0] - p[1], p[2] - p[3], p[4] - p[5])
        self.permanent = (np.abs(p[0]) + np.abs(p[1]), np.abs(p[2]) + np.abs(p[3]),
                          np.abs(p[4]) + np.abs(p[5]))

    def side(self, x: np.ndarray) -> np.ndarray:
        """``orient3d(a, b, c, x)`` row by row: ``(k,)`` int8 in {-1, 0, 1}.

        Parameters
        ----------
        x : (k, 3) float64
        """
        if not self.safe:
            return exact_orient3d(self.a, self.b, self.c, x)
        wx, wy, wz = (x[:, i] - self.a[:, i] for i in range(3))
        n, p = self.normal, self.permanent
        det = (n[0] * wx + n[1] * wy) + n[2] * wz
        perm = (np.abs(wx) * p[0] + np.abs(wy) * p[1]) + np.abs(wz) * p[2]
        out = _signs(det)
        unsure = np.abs(det) <= O3D_BOUND * perm
        unsure &= perm != 0             # a zero permanent: every product, so det, exactly zero
        if unsure.any():
            rows = np.flatnonzero(unsure)
            out[rows] = exact_orient3d(self.a[rows], self.b[rows], self.c[rows], x[rows])
        return out


    def facing(self, d: np.ndarray) -> np.ndarray:
        """Exact signs of ``((b - a) × (c - a)) · d`` for vectors ``d`` ``(k, 3)`` (taken as
        exact: no difference is rounded), row by row: where the plane's normal points along."""
        if not self.safe:
            return exact_turn(self.b, self.c, d, self.a)
        n, p = self.normal, self.permanent
        det = (n[0] * d[:, 0] + n[1] * d[:, 1]) + n[2] * d[:, 2]
        perm = (np.abs(d[:, 0]) * p[0] + np.abs(d[:, 1]) * p[1]) + np.abs(d[:, 2]) * p[2]
        out = _signs(det)
        unsure = (np.abs(det) <= O3D_BOUND * perm) & (perm != 0)
        if unsure.any():
            rows = np.flatnonzero(unsure)
            out[rows] = exact_turn(self.b[rows], self.c[rows], d[rows], self.a[rows])
        return out


def turn(a: np.ndarray, b: np.ndarray, r: np.ndarray, n: np.ndarray, safe: bool = True) -> np.ndarray:
    """Exact signs of ``det[b - a, r, n]`` for points ``a, b`` and exact vectors ``r, n`` (all
    ``(k, 3)``): the side of ``b - a`` from ``r`` seen along ``n``, ``(k,)`` int8. The minors of
    ``r`` and ``n`` and their dot product with the rounded ``b - a`` have Shewchuk's structure,
    so his bound holds."""
    if not safe:
        return -exact_turn(r, b, n, a, vectors=True)
    p = (r[:, 1] * n[:, 2], r[:, 2] * n[:, 1], r[:, 2] * n[:, 0], r[:, 0] * n[:, 2], r[:, 0] * n[:, 1],
         r[:, 1] * n[:, 0])
    minor = (p[0] - p[1], p[2] - p[3], p[4] - p[5])
    x = (b[:, 0] - a[:, 0], b[:, 1] - a[:, 1], b[:, 2] - a[:, 2])
    det = (x[0] * minor[0] + x[1] * minor[1]) + x[2] * minor[2]
    perm = ((np.abs(x[0]) * (np.abs(p[0]) + np.abs(p[1])) + np.abs(x[1]) * (np.abs(p[2]) + np.abs(p[3])))
            + np.abs(x[2]) * (np.abs(p[4]) + np.abs(p[5])))
    out = _signs(det)
    unsure = (np.abs(det) <= O3D_BOUND * perm) & (perm != 0)
    if unsure.any():
        rows = np.flatnonzero(unsure)
        out[rows] = -exact_turn(r[rows], b[rows], n[rows], a[rows], vectors=True)
    return out


def exact_turn(b: np.ndarray, c: np.ndarray, d: np.ndarray, a: np.ndarray, vectors: bool = False) -> np.ndarray:
    """``det[b - a, c - a, d]`` in integers; with ``vectors``, ``det[b, c - a, d]`` (``b`` a
    vector, not a point): the exact stage of ``Planes.facing`` and ``turn``."""
    rows = _integers(np.concatenate([a, b, c, d], axis=1))
    out = np.empty(len(rows), dtype=np.int8)
    for i, (ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz) in enumerate(rows):
        if not vectors:
            bx, by, bz = bx - ax, by - ay, bz - az
        ux, uy, uz = bx, by, bz
        vx, vy, vz = cx - ax, cy - ay, cz - az
        out[i] = _sign(dx * (uy * vz - uz * vy) + dy * (uz * vx - ux * vz) + dz * (ux * vy - uy * vx))
    return out


def orient3d(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, safe: bool = True) -> np.ndarray:
    """Exact signs of ``((b - a) × (c - a)) · (d - a)``, row by row (``(k, 3)`` float64 each)."""
    return Planes(a, b, c, safe).side(d)


def orient2d(a: np.ndarray, b: np.ndarray, c: np.ndarray, safe: bool = True) -> np.ndarray:
    """Exact signs of ``(b - a) × (c - a)`` for ``(k, 2)`` float64 points: ``(k,)`` int8."""
    if not safe:
        return exact_orient2d(a, b, c)
    return _filtered_orient2d(a[:, 0], a[:, 1], b[:, 0], b[:, 1], c,
                              lambda rows: exact_orient2d(a[rows], b[rows], c[rows]))


def orient2d_about(a: np.ndarray, b: np.ndarray, c: np.ndarray, safe: bool = True) -> np.ndarray:
    """``orient2d`` of one ``a`` and one ``b`` ``(2,)`` with every ``c`` ``(k, 2)``: the same
    exact signs, without spreading ``a`` and ``b`` to arrays (the same float operations, so the
    filter decides the same rows)."""
    def spread(rows: np.ndarray | int) -> tuple[np.ndarray, np.ndarray]:
        shape = (rows, 2) if isinstance(rows, int) else (rows.size, 2)
        return np.broadcast_to(a, shape), np.broadcast_to(b, shape)

    if not safe:
        return exact_orient2d(*spread(len(c)), c)
    return _filtered_orient2d(a[0], a[1], b[0], b[1], c, lambda rows: exact_orient2d(*spread(rows), c[rows]))


def _filtered_orient2d(ax, ay, bx, by, c: np.ndarray, exact) -> np.ndarray:
    """orient2d's float filter (``a``, ``b`` as arrays of ``c``'s rows or as single values: the
    same operations either way), with ``exact(rows)`` for the rows it cannot decide."""
    cx, cy = c[:, 0], c[:, 1]
    left = (ax - cx) * (by - cy)
    right = (ay - cy) * (bx - cx)
    det = left - right
    out = _signs(det)
    perm = np.abs(left) + np.abs(right)
    unsure = (np.abs(det) <= CCW_BOUND * perm) & (perm != 0)
    if unsure.any():
        rows = np.flatnonzero(unsure)
        out[rows] = exact(rows)
    return out


def _signs(det: np.ndarray) -> np.ndarray:
    return (det > 0).astype(np.int8) - (det < 0).astype(np.int8)


def _integers(points: np.ndarray) -> list[list[int]]:
    """Each row's coordinates as integers on one power-of-two grid: ``(k, m)`` float64 ->
    ``k`` lists of ``m`` ints ``x · 2**-e`` with ``e`` the smallest exponent of the row (the
    scale is positive, so signs of polynomials homogeneous in the differences are kept)."""
    mantissa, exponent = np.frexp(points)
    ints = (mantissa * 2.0 ** 53).astype(np.int64)          # exact: |mantissa| < 1, 53 bits
    exponent = exponent.astype(np.int64)
    exponent[ints == 0] = np.iinfo(np.int64).max // 2       # zeros do not set the grid
    shift = exponent - exponent.min(axis=1, keepdims=True)
    shift[ints == 0] = 0
    return [[m << s for m, s in zip(row_m, row_s)]
            for row_m, row_s in zip(ints.tolist(), shift.tolist())]


def _sign(value: int) -> int:
    return (value > 0) - (value < 0)


def exact_orient3d(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> np.ndarray:
    """``orient3d`` in integer arithmetic, for rows the filter could not decide."""
    rows = _integers(np.concatenate([a, b, c, d], axis=1))
    out = np.empty(len(rows), dtype=np.int8)
    for i, (ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz) in enumerate(rows):
        ux, uy, uz, vx, vy, vz = bx - ax, by - ay, bz - az, cx - ax, cy - ay, cz - az
        wx, wy, wz = dx - ax, dy - ay, dz - az
        out[i] = _sign(wx * (uy * vz - uz * vy) + wy * (uz * vx - ux * vz) + wz * (ux * vy - uy * vx))
    return out


def exact_orient2d(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """``orient2d`` in integer arithmetic, for rows the filter could not decide."""
    rows = _integers(np.concatenate([a, b, c], axis=1))
    out = np.empty(len(rows), dtype=np.int8)
    for i, (ax, ay, bx, by, cx, cy) in enumerate(rows):
        out[i] = _sign((bx - ax) * (cy - ay) - (by - ay) * (cx - ax))
    return out


def orient3d_fraction(a, b, c, d) -> int:
    """``orient3d`` of four points (sequences of floats or Fractions) in rational arithmetic:
    the slow, obviously exact reference the tests and the rare cases use."""
    a, b, c, d = ([Fraction(x) for x in p] for p in (a, b, c, d))
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    w = [d[i] - a[i] for i in range(3)]
    det = (w[0] * (u[1] * v[2] - u[2] * v[1]) + w[1] * (u[2] * v[0] - u[0] * v[2])
           + w[2] * (u[0] * v[1] - u[1] * v[0]))
    return _sign(det.numerator)


def orient2d_fraction(a, b, c) -> int:
    """``orient2d`` of three 2-D points in rational arithmetic."""
    a, b, c = ([Fraction(x) for x in p] for p in (a, b, c))
    det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    return _sign(det.numerator)
