"""Volume integrals of closed triangle meshes and tetrahedral meshes (the Physics3D note's section 1.3).

Every triangle ``(a, b, c)`` spans, with a local origin ``o``, the signed tetrahedron
``(o, a, b, c)``; by the divergence theorem the sum of these tetrahedra's integrals is the
solid's integral, whatever ``o`` is, for a closed consistently wound mesh (docs/method.md, "Divergence theorem"). For a
tetrahedron with vertices ``p0 = 0, p1, p2, p3`` and ``D = det[p1 p2 p3]`` (Tonon 2004, the
standard simplex integrals):

- ``∫ dV = D / 6``
- ``∫ x dV = D (p1 + p2 + p3) / 24``
- ``∫ x xᵀ dV = D (p1 p1ᵀ + p2 p2ᵀ + p3 p3ᵀ + s sᵀ) / 120`` with ``s = p1 + p2 + p3``.

These are algebraically the note's eq. 12-16 (with the eq. 12 typo fixed), summed per triangle.

Precision: the local origin ``o`` is placed inside the part's bounding box, so the summed
terms have the part's size, not its distance from the world origin, and the second moments are
shifted to the centre of mass once at the end. A part translated by 1e8 then keeps the relative
accuracy it has at the origin (docs/method.md, "Precision far from the origin"). Terms are summed
pairwise within a block (``numpy.sum``) and the block totals with ``math.fsum``.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from p3d_cli.mesh.columns import columns, local_origin
from p3d_cli.results import MomentErrors, Moments

#: Number of summed quantities: 6V, 24·first (3), 120·second (xx, yy, zz, xy, xz, yz).
N_SUMS = 10
_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))
_UNIT_ROUNDOFF = np.finfo(np.float64).eps / 2
_SMALLEST = 2.0 ** -1074


def tetra_terms(p1: np.ndarray, p2: np.ndarray, p3: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per-tetrahedron terms of the sums, for tetrahedra ``(0, p1, p2, p3)``.

    Parameters
    ----------
    p1, p2, p3 : (3, n) float64
        Vertex coordinates relative to the local origin, one row per axis.

    Returns
    -------
    terms : (10, n) float64
        Rows: ``D``, ``D s`` (3 rows), ``D q_ij`` for ij in xx, yy, zz, xy, xz, yz, where
        ``D = det[p1 p2 p3]``, ``s = p1 + p2 + p3`` and
        ``q_ij = p1_i p1_j + p2_i p2_j + p3_i p3_j + s_i s_j``.
    magnitude : (n,) float64
        ``Σ_i |p1_i| (|e1_j e2_k| + |e1_k e2_j|)``: the sum of the magnitudes of the products
        that make up ``D``. ``D``'s rounding error is a small multiple of it times the unit
        roundoff; on a sliver face ``D`` itself cancels far below it.
    weighted : (3,) float64
        ``Σ magnitude · q_ii`` for i = x, y, z: with Cauchy-Schwarz these bound the magnitudes
        of every row's terms (see ``_abs_bounds``).

    Notes
    -----
    ``D`` is computed as ``p1 · ((p2 - p1) × (p3 - p1))``, which equals ``p1 · (p2 × p3)``
    exactly but crosses two short edge vectors instead of two long position vectors, so only
    the face's own shape, not its distance from the origin, limits the cross product's accuracy.
    """
    n = p1.shape[1]
    out = np.empty((N_SUMS, n))
    # Products go into reused buffers (out=...): the block is a few MB and fresh temporaries
    # would cost page faults and cache misses, not arithmetic.
    t = np.empty(n)
    u = np.empty(n)
    magnitude = np.empty(n)
    det = out[0]
    determinants(p1, p2, p3, det, magnitude, t, u)
    # s = p1 + p2 + p3
    s = np.add(p1, p2)
    s += p3
    np.multiply(det, s, out=out[1:4])
    # q_ij = p1_i p1_j + p2_i p2_j + p3_i p3_j + s_i s_j, times det
    weighted = np.empty(3)
    for row, (i, j) in enumerate(_PAIRS, start=4):
        q = np.multiply(p1[i], p1[j], out=u)
        q += np.multiply(p2[i], p2[j], out=t)
        q += np.multiply(p3[i], p3[j], out=t)
        q += np.multiply(s[i], s[j], out=t)
        if i == j:
            # Not np.dot: above a few thousand elements OpenBLAS splits a dot product over
            # threads, which on a busy machine (CI, a batch run) wait for each other and
            # tripled the whole run's time. All terms are >= 0, so any summation order is
            # accurate to n·eps relative, far inside the bound's 1.01 margin.
            weighted[i] = np.multiply(magnitude, q, out=t).sum()
        np.multiply(q, det, out=out[row])
    return out, magnitude, weighted


def determinants(p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, det: np.ndarray, magnitude: np.ndarray,
                 t: np.ndarray | None = None, u: np.ndarray | None = None) -> None:
    """Row 0 of ``tetra_terms``, ``D = p1 · ((p2 - p1) × (p3 - p1))``, and its magnitude (the
    one copy of this formula; ``p3d_cli.mesh.volume`` streams it alone), written into ``det``
    and ``magnitude`` (``(n,)``); ``t`` and ``u`` are optional ``(n,)`` scratch buffers."""
    n = det.shape[0]
    t = np.empty(n) if t is None else t
    u = np.empty(n) if u is None else u
    e1 = np.subtract(p2, p1)
    e2 = np.subtract(p3, p1)
    det[:] = 0.0
    magnitude[:] = 0.0
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        # cross_i = e1_j e2_k - e1_k e2_j;  D += p1_i cross_i
        np.multiply(e1[j], e2[k], out=t)
        np.multiply(e1[k], e2[j], out=u)
        cross = np.subtract(t, u)
        cross *= p1[i]
        det += cross
        np.abs(t, out=t)
        np.abs(u, out=u)
        t += u
        t *= np.abs(p1[i], out=u)
        magnitude += t


def _abs_bounds(total_magnitude: float, weighted: np.ndarray) -> np.ndarray:
    """Bounds on ``Σ |term|`` (and on the magnitudes each term is computed from), per row.

    With ``m = magnitude`` of each ``D`` and ``q_ii`` the diagonal factors:
    ``|s_i| <= |p1_i| + |p2_i| + |p3_i| <= sqrt(3 q_ii)``, so by Cauchy-Schwarz
    ``Σ m |s_i| <= sqrt(3 Σm · Σ m q_ii)``; ``|q_ij|`` with its products' magnitudes
    ``<= (q_ii + q_jj) / 2``. The 1.01 covers the rounding of these sums themselves. The square
    root is taken of each factor: their product (size⁸) overflows for parts of size 1e40 and
    underflows below 1e-39, where the factors themselves (size³, size⁵) are still in range.
    """
    out = np.empty(N_SUMS)
    out[0] = total_magnitude
    out[1:4] = np.sqrt(3.0 * total_magnitude) * np.sqrt(weighted)
    for row, (i, j) in enumerate(_PAIRS, start=4):
        out[row] = 0.5 * (weighted[i] + weighted[j])
    return out * 1.01


def _term_scales(radius: np.ndarray, first: float, second: float) -> np.ndarray:
    """Bounds on the factor multiplying ``D`` in each row, for coordinates within ``radius``.

    ``|s_i| <= first·r_i`` and ``|q_ij|`` (with the magnitudes of its products) ``<= second·r_i r_j``.
    """
    scales = np.empty(N_SUMS)
    scales[0] = 1.0
    scales[1:4] = first * radius
    for row, (i, j) in enumerate(_PAIRS, start=4):
        scales[row] = second * radius[i] * radius[j]
    return scales


class MomentSums:
    """Running sums of tetrahedron terms about a fixed local origin (internal accumulator).

    Feed it blocks of triangles (``add_triangles``) or tetrahedra (``add_tetrahedra``), then
    read the result with ``moments()``. Block totals are kept and summed with ``math.fsum``.
    """

    def __init__(self, origin: np.ndarray) -> None:
        self.origin = np.asarray(origin, dtype=np.float64).reshape(3)
        self._totals: list[np.ndarray] = []
        self._abs_totals: list[np.ndarray] = []
        self.count = 0
        self.inverted = 0          # tetrahedra given with negative orientation
        self._longest_block = 1

    def add_triangles(self, triangles: np.ndarray) -> None:
        """Add triangles ``(n, 3, 3)`` (any float dtype; widened to float64 before arithmetic)."""
        self.add_columns(columns(triangles))

    def add_columns(self, columns: np.ndarray) -> None:
        """Add triangles given as float64 columns, the layout the one-pass analysis reads into.

        Parameters
        ----------
        columns : (3, 3, n) float64, C-contiguous
            Vertex slot, axis, triangle; world coordinates. Overwritten: shifted in place to
            the local origin (the caller has no further use for it, and a copy would cost a
            pass over the block).
        """
        columns -= self.origin[None, :, None]
        terms, magnitude, weighted = tetra_terms(columns[0], columns[1], columns[2])
        self._add(terms, _abs_bounds(float(magnitude.sum()), weighted))

    def add_sums(self, totals: np.ndarray, magnitude: float, weighted: np.ndarray, n: int) -> None:
        """Add a block of ``n`` triangles summed elsewhere (``p3d_cli.mesh.kernels``): its row
        totals, the sum of its ``magnitude`` and its ``weighted`` sums, as ``add_columns``
        computes them from ``tetra_terms``."""
        if n == 0:
            return
        self._totals.append(totals)
        self._abs_totals.append(_abs_bounds(magnitude, weighted))
        self.count += n
        self._longest_block = max(self._longest_block, n)

    def add_tetrahedra(self, tetrahedra: np.ndarray) -> None:
        """Add tetrahedra ``(n, 4, 3)``: each contributes its own signed volume integrals."""
        local = _local_columns(tetrahedra, self.origin)
        p0 = local[0]
        # Shift each tetrahedron so that p0 is its origin, then move its integrals back:
        # a tetra (p0, p1, p2, p3) equals tetra (0, p1-p0, p2-p0, p3-p0) translated by p0.
        e1, e2, e3 = local[1] - p0, local[2] - p0, local[3] - p0
        terms, magnitude, _ = tetra_terms(e1, e2, e3)
        # Each tetrahedron of a volume mesh is a piece of material whatever the order of its
        # vertices (generators such as Delaunay do not orient them): count it positive, and
        # remember how many were listed inside out.
        inverted = terms[0] < 0
        self.inverted += int(inverted.sum())
        terms *= np.where(inverted, -1.0, 1.0)
        det, s = terms[0], e1 + e2 + e3
        # About the shared origin: ∫x = D/24 (s + 4 p0); ∫x xᵀ = ∫(y+p0)(y+p0)ᵀ with y local.
        first = det * (s + 4 * p0)
        second = np.empty((6, det.shape[0]))
        for row, (i, j) in enumerate(_PAIRS):
            second[row] = (terms[4 + row] + 5 * det * (s[i] * p0[j] + s[j] * p0[i])
                           + 20 * det * p0[i] * p0[j])
        # Edges are within 2r, so |s + 4 p0| <= 10 r and the shifted second-moment factor
        # (q of the edges, 5 |s| |p0| twice, 20 |p0|²) <= 128 r_i r_j.
        scales = _term_scales(_radius(local), 10.0, 128.0)
        self._add(np.vstack([det[None], first, second]), float(magnitude.sum()) * scales)

    def _add(self, terms: np.ndarray, abs_bounds: np.ndarray) -> None:
        """Add a block's terms; ``abs_bounds`` bounds the block's absolute terms and, times a
        few unit roundoffs, the rounding error of computing them."""
        n = terms.shape[1]
        if n == 0:
            return
        self._totals.append(terms.sum(axis=1))
        self._abs_totals.append(abs_bounds)
        self.count += n
        self._longest_block = max(self._longest_block, n)

    def totals(self) -> tuple[np.ndarray, np.ndarray]:
        """Exactly rounded sums of the block totals, and bounds on the sums of absolute terms."""
        if not self._totals:
            return np.zeros(N_SUMS), np.zeros(N_SUMS)
        blocks = np.array(self._totals)
        with np.errstate(all="ignore"):
            if not np.isfinite(blocks).all():
                # fsum refuses inf - inf; the plain sum's inf or nan is refused downstream (one
                # RangeError: the moments overflow float64).
                return blocks.sum(axis=0), np.array(self._abs_totals).sum(axis=0)
        total = np.array([_fsum(blocks[:, k]) for k in range(N_SUMS)])
        return total, np.array(self._abs_totals).sum(axis=0)

    def moments(self, extra: list[Fraction] | None = None, extra_error: np.ndarray | None = None) -> Moments:
        """The solid's ``Moments``; volume 0 and no centre when the sum is within rounding of 0.

        Parameters
        ----------
        extra : list of 10 Fraction, optional
            Exact terms to add to the totals (an open mesh's boundary terms,
            ``p3d_cli.mesh.boundary.boundary_terms``); the sum and the shift to the centre are
            then done exactly and rounded once, so that a centre far from the local origin
            loses nothing to cancellation.
        extra_error : (10,) array_like, optional
            Bounds on the errors of ``extra``, added to the sums' rounding bounds (and so
            carried into the result's uncertainty).
        """
        total, abs_total = self.totals()
        # A-priori rounding bound per summed quantity. Each term D·f: D's error is at most
        # ~6 roundings of its products' magnitudes, f's a few roundings of its own magnitude
        # (bounded by the term scales), the product one more (~12 in all); pairwise summation
        # of a block adds at most ~log2(n) + 8 roundings of the absolute sum.
        rounding = (20 + math.log2(self._longest_block)) * _UNIT_ROUNDOFF
        # Below float64's normal range (tiny parts: second moments go as size⁵) a rounding
        # loses up to half the smallest subnormal, whatever the magnitudes: ~40 operations per
        # term, each at most 2^-1075 off. Negligible for any part of ordinary size.
        bound = rounding * abs_total + 40 * self.count * _SMALLEST
        if extra_error is not None:
            bound = bound + np.asarray(extra_error, dtype=np.float64)
        if extra is not None:
            if np.isfinite(total).all():
                try:
                    return _exact_finish(self.origin, [Fraction(float(t)) + e for t, e in zip(total, extra)], bound)
                except OverflowError:   # an exact result beyond float64
                    pass
            # Sums or a result beyond float64: infinite moments, which the caller's range check
            # turns into one RangeError, as for a closed mesh that overflows.
            inf = math.inf
            return Moments(inf, np.full(3, inf), np.full((3, 3), inf),
                           MomentErrors(inf, np.full(3, inf), np.full((3, 3), inf)))
        volume = volume_from(total[0], bound[0])
        volume_error = bound[0] / 6.0
        if self.count == 0 or volume == 0.0:
            return Moments(0.0, None, None, MomentErrors(volume_error, np.zeros(3), np.zeros((3, 3))))
        first = total[1:4] / 24.0
        second = np.empty((3, 3))
        for row, (i, j) in enumerate(_PAIRS):
            second[i, j] = second[j, i] = total[4 + row] / 120.0
        offset = first / volume                      # centre relative to the local origin
        central = second - volume * np.outer(offset, offset)
        central = 0.5 * (central + central.T)
        center = self.origin + offset
        errors = _errors(volume, offset, bound, volume_error)
        return Moments(volume, center, central, errors)


def volume_from(total: float | Fraction, bound: float) -> float:
    """The volume from the summed ``6V`` and its rounding bound: 0.0 within the bound.

    The one rule ``p3d props`` and ``p3d check`` share (``total / 6`` rounded once). A sum or
    bound beyond float64 (coordinates past about 1e100) gives NaN, never a rounded-away 0,
    so that both refuse it as out of range.
    """
    if not math.isfinite(bound) or (not isinstance(total, Fraction) and not math.isfinite(total)):
        return math.nan
    if isinstance(total, Fraction):
        return 0.0 if abs(total) <= Fraction(bound) else float(total / 6)
    return 0.0 if abs(total) <= bound else float(total) / 6.0


def _fsum(values) -> float:
    """``math.fsum``, also when its partial sums overflow float64 (it raises then): the values
    are summed scaled by 2^-64 (exact but for subnormal parts, negligible beside values near
    1e308) and scaled back, which is inf only when the sum itself is out of range."""
    try:
        return math.fsum(values)
    except OverflowError:
        return math.fsum(float(v) * 2.0 ** -64 for v in values) * 2.0 ** 64


def _exact_finish(origin: np.ndarray, total: list[Fraction], bound: np.ndarray) -> Moments:
    """``moments()`` from exact totals: ``c = F/V`` and ``C = S - V c cᵀ`` in rationals."""
    volume = volume_from(total[0], bound[0])
    volume_error = bound[0] / 6.0
    if volume == 0.0:
        return Moments(0.0, None, None, MomentErrors(volume_error, np.zeros(3), np.zeros((3, 3))))
    v = total[0] / 6
    offset = [t / 24 / v for t in total[1:4]]
    central = np.empty((3, 3))
    for row, (i, j) in enumerate(_PAIRS):
        central[i, j] = central[j, i] = float(total[4 + row] / 120 - v * offset[i] * offset[j])
    center = np.array([float(Fraction(float(o)) + d) for o, d in zip(origin, offset)])
    offset_float = np.array([float(d) for d in offset])
    return Moments(volume, center, central, _errors(volume, offset_float, bound, volume_error))


def _errors(volume, offset, bound, volume_error) -> MomentErrors:
    """Propagate the summation bounds through ``c = F/V`` and ``C = S - V c cᵀ`` (first order)."""
    first_error = bound[1:4] / 24.0
    rel_v = volume_error / abs(volume)
    center_error = (first_error / abs(volume) + np.abs(offset) * rel_v) * 1.01
    second_error = np.empty((3, 3))
    for row, (i, j) in enumerate(_PAIRS):
        second_error[i, j] = second_error[j, i] = bound[4 + row] / 120.0
    a = np.abs(offset)
    shift_error = (volume_error * np.outer(a, a)
                   + abs(volume) * (np.outer(center_error, a) + np.outer(a, center_error)))
    ulp_terms = 4 * _UNIT_ROUNDOFF * abs(volume) * np.outer(a, a)
    central_error = (second_error + shift_error + ulp_terms) * 1.01
    return MomentErrors(volume_error, center_error, central_error)


def _radius(local: np.ndarray) -> np.ndarray:
    """Largest ``|coordinate|`` per axis of a ``(k, 3, n)`` block relative to the local origin."""
    if local.shape[2] == 0:
        return np.zeros(3)
    return np.maximum(local.max(axis=(0, 2)), -local.min(axis=(0, 2)))


def _local_columns(points: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """``points - origin`` in float64 as ``(k, 3, n)``: vertex slot, axis, element."""
    local = columns(points)
    local -= origin[None, :, None]
    return local


def triangle_moments(triangles: np.ndarray, origin=None, block: int = 65536) -> Moments:
    """Moments of the solid bounded by ``triangles``.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64
        Corner coordinates; counter-clockwise seen from outside for a positive volume.
    origin : (3,) array_like, optional
        Local origin of the sums; default the centre of the triangles' bounding box.
    block : int
        Triangles per summed block.
    """
    triangles = np.asarray(triangles)
    if origin is None:
        origin = local_origin(triangles)
    sums = MomentSums(origin)
    for start in range(0, len(triangles), block):
        sums.add_triangles(triangles[start:start + block])
    return sums.moments()


def tetrahedron_moments(tetrahedra: np.ndarray, origin=None, block: int = 65536) -> Moments:
    """Moments of a tetrahedral volume mesh; every tetrahedron counts positive, whatever the
    order of its vertices (``tetrahedron_sums`` also tells how many were inverted).

    Parameters
    ----------
    tetrahedra : (n, 4, 3) float64
    """
    return tetrahedron_sums(tetrahedra, origin, block).moments()


def tetrahedron_sums(tetrahedra: np.ndarray, origin=None, block: int = 65536) -> MomentSums:
    """The accumulated sums of a tetrahedral mesh (``.moments()``, ``.inverted``)."""
    tetrahedra = np.asarray(tetrahedra)
    if origin is None:
        origin = local_origin(tetrahedra)
    sums = MomentSums(origin)
    for start in range(0, len(tetrahedra), block):
        sums.add_tetrahedra(tetrahedra[start:start + block])
    return sums
