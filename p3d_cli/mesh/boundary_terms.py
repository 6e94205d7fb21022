"""Fast, accurate boundary terms ``Σ T(0, o, u, v)`` of an open mesh, for any number of sides.

``p3d_cli.mesh.boundary`` explains why an open mesh's world-convention sums are its local sums
about ``o`` plus ``Σ T(0, o, u, v)`` over its net boundary ``u→v``. Far from the world origin
these terms are huge (``|o|³ L²`` for a part of size ``L`` at distance ``|o|``) and cancel to
something of size ``L⁵``; this module computes them to ~100 bits without Python integers per
side (docs/method.md, "Open and non-manifold meshes").

Reduction to local sums. With a second point ``o'`` (chosen so that every ``a = u - o'`` is
an exact float, ``frame_origin``) the 4-simplex ``[0, o, o', u, v]`` has a zero boundary, so
summed over a cycle of sides (the two terms with ``o, o'`` and one moving vertex cancel)

    Σ T(0, o, u, v) = Σ T(0, o', u, v) - Σ T(o, o', u, v).

Each tetrahedron ``(A, o', o' + a, o' + b)`` has ``D = g·(a × b)`` with ``g = o' - A``, so
its integrals are polynomials in the constants ``g`` times the local sums, ``X = a × b`` and
``t = a + b``:

- ``P_k = Σ X_k`` (3), exact: each product split exactly by ``two_product`` and the parts
  summed by ``ExactSum``. On a cycle it equals ``Σ u × v`` in world coordinates, which is how
  ``p3d check`` gets the same volume term without the local frame (``WorldCross``);
- ``Q_ki = Σ X_k t_i`` (9) and ``R_kij = Σ X_k w_ij`` (18),
  ``w_ij = a_i a_j + b_i b_j + t_i t_j``: each term in double-double (~106 bits), its high
  part summed exactly (``Q``, which the result multiplies by ``|o|²``) or by cascaded
  error-free sums (``R``, multiplied by ``|o|`` only), its low part in float64, with the
  a-priori bound of ``Locals``.

The ten sums then follow in ``Fraction`` arithmetic (``combine``), a few hundred operations per
mesh, and so does their error bound (the same formula with absolute values).
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import NamedTuple

import numpy as np

from p3d_cli.geometry.expansions import (
    TINY,
    UNIT,
    ExactSum,
    cascade_factor,
    cascaded_sums,
    product_of_splits,
    split,
    two_product,
    two_sum,
)
from p3d_cli.mesh.kernels import compiled

PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_CYCLE = ((0, 1, 2), (1, 2, 0), (2, 0, 1))
#: X_k = a_i b_j - a_j b_i for (k, i, j) cyclic, as index arrays over k.
_I, _J = np.array([1, 2, 0]), np.array([2, 0, 1])
#: The pairs (i, j) of PAIRS as index arrays.
_PI, _PJ = np.array([i for i, _ in PAIRS]), np.array([j for _, j in PAIRS])
#: The quantity of each of the cross products' four parts (``ExactSum`` rows).
_CROSS_ROWS = np.repeat(np.arange(3), 4)
#: The rows of Q (``ExactSum`` rows), and the sides whose exact parts are added at once.
_Q_ROWS = np.arange(9)
#: The rows of each batch's 27 low sums and 18 high sums of R (``ExactSum`` rows).
_SUM_ROWS = np.arange(45)
_BATCH = 1 << 13
#: World coordinates up to this magnitude keep ``two_product`` exact (products below 2**960).
WORLD_LIMIT = 2.0 ** 480
#: Products below this may lose bits to underflow (``two_product``'s error term is subnormal).
_UNDERFLOW = 2.0 ** -968


class InexactLocal(Exception):
    """Raised when ``u - o'`` is not exact for some side (``frame_origin`` rules it out)."""


def frame_origin(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """A point ``o'`` near the box ``[lo, hi]`` with ``u - o'`` exact for every ``u`` in it.

    Per axis: when ``0 < lo <= hi <= 3 lo`` the box's midpoint lies in ``[hi/2, 2 lo]``, so
    ``u/2 <= o' <= 2u`` for every ``u`` and ``u - o'`` is exact (Sterbenz's lemma); mirrored
    for negative boxes; otherwise the box reaches within half its own extent of 0 and
    ``o' = 0`` (``u - 0`` is exact) is near enough.
    """
    lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
    out = np.zeros(3)
    for i in range(3):
        a, b = float(lo[i]), float(hi[i])
        if 0.0 < a and b <= 3.0 * a:
            out[i] = min(max(0.5 * a + 0.5 * b, 0.5 * b), 2.0 * a)
        elif b < 0.0 and a >= 3.0 * b:
            out[i] = max(min(0.5 * a + 0.5 * b, 0.5 * a), 2.0 * b)
    return out


class WorldCross:
    """Exact ``P = Σ u × v`` of sides given in world coordinates (see the module notes)."""

    def __init__(self) -> None:
        self._sum = ExactSum(3)
        self.underflow = 0            # sides that may have lost bits to underflow
        self.extra = [Fraction(0)] * 3

    def add(self, u: np.ndarray, v: np.ndarray) -> None:
        """Add sides ``u→v`` given as ``(3, m)`` world coordinates (finite)."""
        if u.shape[1] == 0:
            return
        biggest = max(float(np.abs(u).max()), float(np.abs(v).max()))
        if biggest >= WORLD_LIMIT:
            self._add_exactly(u, v)       # absurd coordinates: exact integers, slowly
            return
        parts = np.empty((12, u.shape[1]))
        small = np.zeros(u.shape[1], dtype=bool)
        for k, i, j in _CYCLE:
            p1, e1 = two_product(u[i], v[j])
            p2, e2 = two_product(u[j], v[i])
            parts[4 * k], parts[4 * k + 1], parts[4 * k + 2], parts[4 * k + 3] = p1, e1, -p2, -e2
            for p in (p1, p2):
                small |= (p != 0.0) & (np.abs(p) < _UNDERFLOW)
        self._sum.add(parts, np.repeat(np.arange(3), 4))
        self.underflow += int(small.sum())

    def _add_exactly(self, u: np.ndarray, v: np.ndarray) -> None:
        pu = [[Fraction(x) for x in row] for row in u.tolist()]
        pv = [[Fraction(x) for x in row] for row in v.tolist()]
        for k, i, j in _CYCLE:
            self.extra[k] += sum((pu[i][n] * pv[j][n] - pu[j][n] * pv[i][n] for n in range(len(pu[0]))),
                                 Fraction(0))

    def totals(self) -> tuple[list[Fraction], float]:
        """``P`` exactly (but for underflow) and a bound on what underflow can have lost."""
        exact = self._sum.totals()
        return [x + e for x, e in zip(exact, self.extra)], 16.0 * self.underflow * TINY


class Locals:
    """``Q`` and ``R`` of sides in local coordinates ``a = (u - o') · 2**-scale`` (``|a| <= 1``).

    Bound (unit roundoff ``ε = 2**-53``; ``T_i = |a_i| + |b_i|``,
    ``W_ij = |a_i a_j| + |b_i b_j| + T_i T_j``, ``m_k = |a_i b_j| + |a_j b_i|`` for ``k, i, j``
    cyclic): ``X_k`` in double-double is within ``1.01 ε² |X_k| + 6.3 ε³ m_k`` (``_cross``),
    ``w_ij`` within ``20 ε² W_ij``, a double-double product adds ``7.2 ε²`` of its magnitude;
    the low parts, each ``<= 1.04 ε`` of the term's magnitude, are summed pairwise per block
    (``numpy.sum``: 8 running sums of up to 16 values in blocks of 128, combined in 3 steps,
    then halving: at most ``log2(n) + 12`` roundings deep). So each ``Q_ki`` is within
    ``(8.3 + 1.04 (log2 n + 12)) ε² Σ |X_k| T_i`` and each ``R_kij`` within
    ``(28 + 1.1 (log2 n + 12) + 1.01 c) ε² Σ |X_k| W_ij`` (``c``: ``cascaded_sums``' factor for
    its high parts), plus ``6.3 ε³ · 12`` (``m_k <= 2``, ``T_i <= 2``, ``W_ij <= 6``) and
    ``256 ε_min`` (underflow) per side.
    """

    def __init__(self) -> None:
        kernels = compiled()
        binner = kernels.exact_bins if kernels is not None else None
        self._high = ExactSum(9, binner)
        self._cross = ExactSum(3, binner)
        # Each batch's 27 low sums and 18 high sums of R, summed exactly at the end.
        self._batch_sums: list[np.ndarray] = []
        self._sums = ExactSum(45, binner)
        self._rounding = np.zeros(27)
        # Parts for the exact sums, added to them in batches (an exact sum is the same in any
        # order and grouping; one ``ExactSum.add`` of a few hundred sides costs as much as of
        # thousands).
        self._waiting: list[tuple[np.ndarray, np.ndarray]] = []
        self._waiting_sides = 0
        self.count = 0
        self.underflow = 0            # sides whose cross products may have lost bits to underflow

    def add(self, u: np.ndarray, v: np.ndarray, frame: np.ndarray, scale: int) -> None:
        """Add sides ``u→v`` given as ``(3, m)`` world coordinates, in the local coordinates
        ``a = (u - frame) · 2**-scale`` (``|a| <= 1``; ``local_coordinates``).

        Raises
        ------
        InexactLocal
            Some ``u - frame`` is not an exact float (``frame_origin`` rules it out).
        """
        n = u.shape[1]
        if n == 0:
            return
        kernels = compiled()
        if kernels is not None:
            terms = _compiled_terms(kernels, u, v, frame, scale)
        else:
            terms = local_terms(local_coordinates(u, frame, scale), local_coordinates(v, frame, scale))
        self.underflow += terms.underflow
        # Q is multiplied by |o|² in the end, R by |o| only: Q's high parts are summed exactly,
        # R's by a cascade of error-free sums (``cascaded_sums``: ~2^-100 of their magnitude,
        # far more than R needs, at a fifth of the cost).
        self._waiting.append((terms.parts, terms.q_high))
        self._waiting_sides += n
        if self._waiting_sides >= _BATCH:
            self._add_waiting()
        self._batch_sums.append(np.concatenate([terms.low_sums, terms.r_sum]))
        self._bound(terms.mag, terms.big_t, terms.big_w, n, cascade_factor(n))

    def _add_waiting(self) -> None:
        """Add the parts set aside to the exact sums."""
        if self._waiting:
            self._cross.add(np.concatenate([x for x, _ in self._waiting], axis=1), _CROSS_ROWS)
            self._high.add(np.concatenate([q for _, q in self._waiting], axis=1), _Q_ROWS)
        self._waiting, self._waiting_sides = [], 0
        if self._batch_sums:
            self._sums.add(np.stack(self._batch_sums, axis=1), _SUM_ROWS)
            self._batch_sums = []

    def _bound(self, mag: np.ndarray, big_t: np.ndarray, big_w: np.ndarray, n: int, cascade: float) -> None:
        """Accumulate ``Σ |X_k| T_i``, ``Σ |X_k| W_ij`` and the block's rounding factors."""
        # Sums of non-negative products: float rounding is far inside the final 1.01 margin.
        q_mag = (mag @ big_t.T).reshape(-1)              # [k, i] -> 3k + i
        r_mag = (mag @ big_w.T).reshape(-1)              # [k, row] -> 6k + row
        low_sum = 1.04 * (math.log2(n) + 12)
        self._rounding[:9] += (8.3 + low_sum) * q_mag
        # |high| <= 1.01 · magnitude, so the cascade's bound is in terms of r_mag too; the low
        # sums (now with the cascade's errors in them) get 3 more roundings (1.04 -> 1.1).
        self._rounding[9:] += (28.0 + 1.1 / 1.04 * low_sum + 1.01 * cascade) * r_mag
        self.count += n

    def cross_totals(self) -> tuple[list[Fraction], float]:
        """``P`` (3) exactly but for underflow, and a bound on what underflow can have lost."""
        self._add_waiting()
        return self._cross.totals(), 16.0 * self.underflow * TINY

    def totals(self) -> tuple[list[Fraction], np.ndarray]:
        """``Q`` (9, ``[3k + i]``) and ``R`` (18, ``[6k + pair]``) and their error bounds."""
        self._add_waiting()
        sums = self._sums.totals()
        low, r_high = sums[:27], sums[27:]
        high = self._high.totals() + r_high
        # X's own u³ term: 6.3 ε³ m_k with m_k <= 2, times T_i <= 2 or W_ij <= 6 (|a|, |b| <= 1).
        cubic = 6.3 * UNIT ** 3 * 12.0 * self.count
        error = 1.01 * (self._rounding * UNIT * UNIT + cubic + 256.0 * self.count * TINY)
        return [h + lo for h, lo in zip(high, low)], error


class Terms(NamedTuple):
    """One batch of sides' numbers for ``Locals`` (``local_terms``)."""

    parts: np.ndarray       # (12, n) the cross products' exact parts, row 4k + part
    q_high: np.ndarray      # (9, n) Q's exact high parts, row 3k + i
    low_sums: np.ndarray    # (27,) Q's and R's low parts summed per row (R's with the cascade's errors)
    r_sum: np.ndarray       # (18,) the cascade's high sums of R
    mag: np.ndarray         # (3, n) |X_k|
    big_t: np.ndarray       # (3, n) T_i = |a_i| + |b_i|
    big_w: np.ndarray       # (6, n) W_ij
    underflow: int          # sides whose cross products may have lost bits to underflow


def local_terms(a: np.ndarray, b: np.ndarray) -> Terms:
    """``Locals.add``'s numbers for sides with scaled local end points ``a``, ``b`` ``(3, n)``,
    ``n >= 1``, in numpy (the compiled ``local_terms`` replays the same operations)."""
    n = a.shape[1]
    # Every product of the same quantities in one numpy call, each value split once
    # (Veltkamp) for all its products: rows (k, i) of Q are 3k + i, rows (k, pair) of R 6k + pair.
    sa, sb = split(a), split(b)
    p1, e1 = product_of_splits(a[_I], _rows(sa, _I), b[_J], _rows(sb, _J))
    p2, e2 = product_of_splits(a[_J], _rows(sa, _J), b[_I], _rows(sb, _I))
    xh, xl, parts = _cross(p1, e1, p2, e2)
    small = ((p1 != 0.0) & (np.abs(p1) < _UNDERFLOW)) | ((p2 != 0.0) & (np.abs(p2) < _UNDERFLOW))
    th, tl = two_sum(a, b)
    sth, sxh = split(th), split(xh)
    q_high, q_low = _dd_product(xh[:, None], _rows(sxh, slice(None), None), xl[:, None],
                                th[None], _rows(sth, None), tl[None])
    wh, wl = _w(a, sa, b, sb, th, sth, tl)
    r_high, r_low = _dd_product(xh[:, None], _rows(sxh, slice(None), None), xl[:, None],
                                wh[None], _rows(split(wh), None), wl[None])
    r_sum, r_sum_low, _ = cascaded_sums(r_high.reshape(18, n))
    low_sums = np.concatenate([q_low.reshape(9, n).sum(axis=1), r_low.reshape(18, n).sum(axis=1)])
    low_sums[9:] += r_sum_low
    abs_a, abs_b = np.abs(a), np.abs(b)
    big_t = abs_a + abs_b
    big_w = np.empty((6, n))
    for row, (i, j) in enumerate(PAIRS):
        big_w[row] = abs_a[i] * abs_a[j] + abs_b[i] * abs_b[j] + big_t[i] * big_t[j]
    return Terms(parts.transpose(1, 0, 2).reshape(12, n), q_high.reshape(9, n), low_sums, r_sum,
                 np.abs(xh), big_t, big_w, int(small.any(axis=0).sum()))


def local_coordinates(u: np.ndarray, frame: np.ndarray, scale: int) -> np.ndarray:
    """``(u - frame) · 2**-scale`` for world coordinates ``u`` ``(3, m)``, checked exact:
    ``two_sum``'s error term is zero, and the scaling lost nothing to underflow (coordinates
    spanning more than 2**1000); else ``InexactLocal``."""
    a, error = two_sum(u, -np.asarray(frame, dtype=np.float64)[:, None])
    scaled = np.ldexp(a, -scale)
    if error.any() or not np.array_equal(np.ldexp(scaled, scale), a):
        raise InexactLocal
    return scaled


def _compiled_terms(kernels, u: np.ndarray, v: np.ndarray, frame: np.ndarray, scale: int) -> Terms:
    """``local_terms`` of ``local_coordinates`` by the compiled kernel: the same bits."""
    n = u.shape[1]
    out = Terms(np.empty((12, n)), np.empty((9, n)), np.empty(27), np.empty(18), np.empty((3, n)),
                np.empty((3, n)), np.empty((6, n)), 0)
    u, v = np.ascontiguousarray(u, dtype=np.float64), np.ascontiguousarray(v, dtype=np.float64)
    underflow = kernels.local_terms(u, v, tuple(float(x) for x in frame), int(scale), out.parts, out.q_high,
                                    out.mag, out.big_t, out.big_w, out.low_sums, out.r_sum)
    if underflow < 0:
        raise InexactLocal
    return out._replace(underflow=underflow)


def _rows(pair: tuple, *index) -> tuple:
    """``(hi[index], lo[index])`` of a ``split`` pair."""
    return pair[0][index], pair[1][index]


def _cross(p1, e1, p2, e2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(p1 + e1) - (p2 + e2)`` (two exact products) in double-double, within
    ``1.01 ε² |high| + 6.3 ε³ m`` of the exact value (``m = |p1| + |p2|``): the four exact
    parts are added with error-free sums first (in the manner of Ogita, Rump and Oishi's
    ``SumK``), so that only parts already ``ε²`` below ``m`` are rounded, and a thin
    triangle's small cross product is as accurate as its own size allows (not just ``ε² m``).

    Returns ``high``, ``low`` and the exact value's four parts ``(4, ...)``."""
    s, t = two_sum(p1, -p2)
    f, g = two_sum(e1, -e2)
    h, c = two_sum(t, f)
    high, d = two_sum(s, h)
    return high, d + (c + g), np.stack([high, d, c, g])


def _dd_product(xh, x_split, xl, yh, y_split, yl) -> tuple[np.ndarray, np.ndarray]:
    """``(xh + xl)(yh + yl)`` as an exact high part and a rounded low part (``xl yl`` dropped),
    broadcasting; ``x_split``, ``y_split``: ``split`` of ``xh`` and ``yh``."""
    p, e = product_of_splits(xh, x_split, yh, y_split)
    e += xh * yl + xl * yh
    return p, e


def _w(a, sa, b, sb, th, sth, tl) -> tuple[np.ndarray, np.ndarray]:
    """``w_ij = a_i a_j + b_i b_j + t_i t_j`` in double-double, one row per ``PAIRS`` entry."""
    x1, y1 = product_of_splits(a[_PI], _rows(sa, _PI), a[_PJ], _rows(sa, _PJ))
    x2, y2 = product_of_splits(b[_PI], _rows(sb, _PI), b[_PJ], _rows(sb, _PJ))
    x3, y3 = product_of_splits(th[_PI], _rows(sth, _PI), th[_PJ], _rows(sth, _PJ))
    y3 += th[_PI] * tl[_PJ] + tl[_PI] * th[_PJ]
    h, l2 = two_sum(x1, x2)
    h, l3 = two_sum(h, x3)
    return two_sum(h, ((y1 + y2) + y3) + (l2 + l3))


def combine(p: list, q: list, r: list, o, frame) -> list:
    """The ten sums of ``Σ T(0, o, u, v)`` about ``o`` from ``P``, ``Q``, ``R`` about ``frame``
    (exact ``Fraction`` in, exact out): ``F(0) - F(o)`` of the module notes."""
    o, frame = [Fraction(float(x)) for x in o], [Fraction(float(x)) for x in frame]
    about_world = _tetra_sums(p, q, r, [-x for x in o], frame)
    about_o = _tetra_sums(p, q, r, [Fraction(0)] * 3, [f - x for f, x in zip(frame, o)])
    return [x - y for x, y in zip(about_world, about_o)]


def combine_bound(p: list, q: list, r: list, o, frame) -> np.ndarray:
    """A bound on ``combine``'s error given bounds ``p, q, r`` on the errors of ``P, Q, R``.

    ``_tetra_sums`` is linear in ``P, Q, R`` with coefficients that are sums of products of
    the constants; evaluated with the errors and the constants' absolute values it bounds each
    coefficient by the sum of its monomials' magnitudes. In float64: every operation adds or
    multiplies non-negative numbers, so each of the ~20 roundings on any path is at most a
    relative ``2**-53``; the 1.000001 covers them (inf if anything overflows).
    """
    o = [abs(float(x)) for x in o]
    frame = [abs(float(x)) for x in frame]
    p, q, r = ([float(x) for x in e] for e in (p, q, r))
    with np.errstate(over="ignore", invalid="ignore"):
        world = _tetra_sums(p, q, r, o, frame)
        local = _tetra_sums(p, q, r, [0.0] * 3, [f + x for f, x in zip(frame, o)])
        out = (np.array(world, dtype=np.float64) + np.array(local, dtype=np.float64)) * 1.000001
    return np.where(np.isnan(out), math.inf, out)


def _tetra_sums(p, q, r, alpha, g) -> list:
    """Ten sums, about the frame origin, of the tetrahedra ``(A, o', o' + a, o' + b)`` with
    ``alpha = A - origin``, ``g = o' - A``: ``D = g·X``; about ``A`` (vertices ``g``,
    ``g + a``, ``g + b``, ``integrals.tetra_terms``) ``Σ D s_i = 3 g_i ΣD + Σ_k g_k Q_ki`` and
    ``Σ D q_ij = 12 g_i g_j ΣD + 4 (g_i Σ_k g_k Q_kj + g_j Σ_k g_k Q_ki) + Σ_k g_k R_kij``;
    then moved by ``alpha`` as ``MomentSums.add_tetrahedra`` moves its tetrahedra."""
    v6 = sum(g[k] * p[k] for k in range(3))
    gq = [sum(g[k] * q[3 * k + i] for k in range(3)) for i in range(3)]
    f1 = [3 * g[i] * v6 + gq[i] for i in range(3)]
    out = [v6] + [f1[i] + 4 * alpha[i] * v6 for i in range(3)]
    for row, (i, j) in enumerate(PAIRS):
        f2 = (12 * g[i] * g[j] * v6 + 4 * g[i] * gq[j] + 4 * g[j] * gq[i]
              + sum(g[k] * r[6 * k + row] for k in range(3)))
        out.append(f2 + 5 * (alpha[i] * f1[j] + alpha[j] * f1[i]) + 20 * alpha[i] * alpha[j] * v6)
    return out
