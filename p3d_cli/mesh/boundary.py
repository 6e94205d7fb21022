"""The net boundary of a triangle soup, and its exact share of the divergence-theorem sums.

Every face side ``u→v`` is a directed edge; the *net boundary* is the multiset of directed
edges left when each ``u→v`` cancels one ``v→u`` (vertices matched by exact coordinates, as in
``p3d_cli.mesh.closed``). When it is empty the faces bound a region (the mesh is *bounding*),
even if some edge is used four or ten times: a closed mesh is bounding, and so are two cubes
sharing an edge.

Why it matters (docs/method.md, "Open and non-manifold meshes"): for any point ``o`` the
boundary of the 4-simplex ``[0, o, a, b, c]`` is zero as a chain, so summed over the faces

    Σ T(0, a, b, c) = Σ T(o, a, b, c) + Σ_{u→v in the net boundary} T(0, o, u, v),

``T`` being a signed tetrahedron's integrals (interior edges cancel pairwise). A bounding
mesh's sums about a local origin are therefore its world sums; an open mesh's world sums are
its accurate local sums plus the boundary terms. ``boundary_terms`` computes them for any
number of sides, streamed from one more pass (exact volume row, ~2^-100 elsewhere, with a
bound: ``p3d_cli.mesh.boundary_terms``); ``boundary_sums`` computes them exactly in Python
integers (every float64 is an integer times a power of two), ~7 µs a side: the tests' oracle
and the fast path's safety net. Which edges are in the net boundary, and their sides as the
file gives them, come from ``p3d_cli.mesh.boundary_sides``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from p3d_cli.mesh.boundary_terms import InexactLocal, Locals, WorldCross, combine, combine_bound, frame_origin
from p3d_cli.mesh.boundary_sides import Unbalanced, block_sides, unbalanced_of, unbalanced_sides
from p3d_cli.mesh.closed import _lex_less, sides_of_edges


@dataclass(frozen=True)
class BoundaryTerms:
    """``Σ T(0, o, u, v)`` over an open mesh's net boundary, in ``MomentSums``' units.

    Attributes
    ----------
    sums : list of 10 Fraction
        The terms (``boundary_terms``): exact in the volume row, within ``error`` elsewhere.
    error : (10,) float64
        Bounds on the error of each sum.
    edges : int
        Directed edges of the net boundary, counted with multiplicity.
    """

    sums: list
    error: np.ndarray
    edges: int


def net_boundary(source_blocks, unbalanced: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The net boundary's distinct directed edges ``u→v`` with their multiplicities.

    Parameters
    ----------
    source_blocks : iterable of (k, 3, 3) arrays
        The triangles, in blocks (read once more).
    unbalanced : (d,) uint64
        Edge ids, ``Unbalanced.ids``.

    Returns
    -------
    start, end : (b, 3) float64
    count : (b,) int64, positive
    """
    empty = (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0, dtype=np.int64))
    if unbalanced.size == 0:
        return empty
    start, end = sides_of_edges(source_blocks, np.sort(unbalanced))
    if start.shape[0] == 0:
        return empty
    # Undirected edge as (lexicographically smaller end, larger end); +1 for each use lo→hi.
    swap = _lex_less(end, start)
    lo = np.where(swap[:, None], end, start)
    hi = np.where(swap[:, None], start, end)
    rows, inverse = np.unique(np.concatenate([lo, hi], axis=1), axis=0, return_inverse=True)
    net = np.bincount(inverse.reshape(-1), weights=np.where(swap, -1.0, 1.0), minlength=rows.shape[0])
    net = np.rint(net).astype(np.int64)
    keep = net != 0
    rows, net = rows[keep], net[keep]
    forward = net > 0
    u = np.where(forward[:, None], rows[:, :3], rows[:, 3:])
    v = np.where(forward[:, None], rows[:, 3:], rows[:, :3])
    return u, v, np.abs(net)


def boundary_of(source_blocks) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``net_boundary`` of triangles read twice from ``source_blocks()`` (a callable)."""
    return net_boundary(source_blocks(), unbalanced_of(source_blocks).ids)


def boundary_sums(start: np.ndarray, end: np.ndarray, count: np.ndarray, origin: np.ndarray) -> list[Fraction]:
    """Exact ``Σ count · T(0, o, u, v)`` about ``o``, in the units of ``MomentSums``' totals.

    Returns the ten sums ``Σ D``, ``Σ D s_i`` and ``Σ D q_ij`` (``integrals.tetra_terms``) of
    the tetrahedra ``(-o, 0, u - o, v - o)``, i.e. ``T(0, o, u, v)`` seen from ``o``:
    ``D = det[o, u, v]``, ``s = (u - o) + (v - o) - o`` and
    ``q = o oᵀ + (u - o)(u - o)ᵀ + (v - o)(v - o)ᵀ + s sᵀ`` (the general simplex integrals,
    docs/method.md, "Divergence theorem").
    """
    if count.size == 0:
        return [Fraction(0)] * 10
    o_int, u_int, v_int, shift = _integers(np.asarray(origin, dtype=np.float64), start, end)
    o = [int(x) for x in o_int]
    a = [u_int[:, i] - o[i] for i in range(3)]
    b = [v_int[:, i] - o[i] for i in range(3)]
    u = [u_int[:, i] for i in range(3)]
    v = [v_int[:, i] for i in range(3)]
    # D = o · (u × v); u, v are world coordinates (exact integers: no cancellation issue).
    det = (o[0] * (u[1] * v[2] - u[2] * v[1]) + o[1] * (u[2] * v[0] - u[0] * v[2])
           + o[2] * (u[0] * v[1] - u[1] * v[0]))
    det = det * np.asarray(count, dtype=object)
    s = [a[i] + b[i] - o[i] for i in range(3)]
    out = [Fraction(int(det.sum()), 1 << (3 * shift))]
    out += [Fraction(int((det * s[i]).sum()), 1 << (4 * shift)) for i in range(3)]
    for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)):
        q = o[i] * o[j] + a[i] * a[j] + b[i] * b[j] + s[i] * s[j]
        out.append(Fraction(int((det * q).sum()), 1 << (5 * shift)))
    return out


def _integers(*arrays: np.ndarray):
    """The arrays as object arrays of Python ints ``k`` with ``x = k · 2**-shift``, and ``shift``."""
    ratios = [[x.as_integer_ratio() for x in np.asarray(arr, dtype=np.float64).reshape(-1).tolist()]
              for arr in arrays]
    shift = max((d.bit_length() - 1 for r in ratios for _, d in r), default=0)
    out = []
    for arr, r in zip(arrays, ratios):
        ints = np.empty(len(r), dtype=object)
        ints[:] = [n << (shift - (d.bit_length() - 1)) for n, d in r]
        out.append(ints.reshape(np.shape(arr)))
    return (*out, shift)


def boundary_volume(source_blocks, unbalanced: Unbalanced, origin: np.ndarray) -> tuple[Fraction, float]:
    """The ``6V`` row of ``boundary_terms`` alone, ``o · Σ u × v`` (the same exact number),
    and a bound on what underflow can have taken from it (0 for any ordinary mesh)."""
    return sides_volume(unbalanced_sides(source_blocks, unbalanced.ids, unbalanced.most), origin)


def sides_volume(sides, origin: np.ndarray) -> tuple[Fraction, float]:
    """``boundary_volume`` of the sides given as ``(3, m)`` start and end columns (world
    coordinates): exact, so any order and any pairs ``u→v``, ``v→u`` besides give the same."""
    cross = WorldCross()
    for u, v in sides:
        cross.add(u, v)
    p, lost = cross.totals()
    o = [Fraction(float(x)) for x in origin]
    return sum((a * b for a, b in zip(o, p)), Fraction(0)), lost * float(np.abs(origin).sum())


def boundary_terms(source_blocks, unbalanced: Unbalanced, origin: np.ndarray,
                   lo: np.ndarray, hi: np.ndarray, picked: list[np.ndarray] | None = None) -> BoundaryTerms:
    """``Σ T(0, o, u, v)`` over the net boundary, any number of sides, ~1 µs a side.

    Parameters
    ----------
    source_blocks : callable
        Returns an iterable of the triangles ``(k, 3, 3)`` (read once more, twice if the fast
        path's local coordinates were not exact, which ``frame_origin`` rules out).
    unbalanced : Unbalanced
        From ``unbalanced_groups``.
    origin : (3,)
        The local origin ``o`` of the moment sums.
    lo, hi : (3,)
        Bounds of the mesh's coordinates.
    picked : list of (m, 6) arrays, optional
        The net boundary's sides already picked block by block (``sides_of_prints``), instead
        of one more pass.
    """
    frame = frame_origin(lo, hi)
    reach = float(np.maximum(np.abs(np.asarray(hi, dtype=np.float64) - frame),
                             np.abs(np.asarray(lo, dtype=np.float64) - frame)).max())
    if not math.isfinite(reach):
        # Coordinates spanning more than float64's range: the moments overflow whatever the
        # terms are; an infinite bound makes that one RangeError downstream.
        return BoundaryTerms([Fraction(0)] * 10, np.full(10, math.inf), unbalanced.edges)
    scale = math.frexp(reach)[1] if reach > 0 else 0          # 2**scale > reach
    local = Locals()
    try:
        sides = (block_sides(picked) if picked is not None
                 else unbalanced_sides(source_blocks(), unbalanced.ids, unbalanced.most))
        for u, v in sides:
            local.add(u, v, frame, scale)
    except InexactLocal:
        sums = _exact_terms(source_blocks, unbalanced, origin)
        return BoundaryTerms(sums, np.zeros(10), unbalanced.edges)
    p, p_error = local.cross_totals()
    qr, qr_error = local.totals()
    unit = Fraction(2) ** scale
    p = [x * unit ** 2 for x in p]
    q = [x * unit ** 3 for x in qr[:9]]
    r = [x * unit ** 4 for x in qr[9:]]
    # Bounds back in the mesh's units; inf when they overflow (so do the moments then: the
    # caller turns that into one RangeError).
    with np.errstate(over="ignore"):
        p_error = float(np.ldexp(p_error, 2 * scale))
        q_error = list(np.ldexp(qr_error[:9], 3 * scale))
        r_error = list(np.ldexp(qr_error[9:], 4 * scale))
    sums = combine(p, q, r, origin, frame)
    error = combine_bound([p_error] * 3, q_error, r_error, origin, frame)
    return BoundaryTerms(sums, error, unbalanced.edges)


def _exact_terms(source_blocks, unbalanced: Unbalanced, origin: np.ndarray) -> list:
    """``boundary_terms`` by exact integer arithmetic on every side (the slow safety net)."""
    total = [Fraction(0)] * 10
    for u, v in unbalanced_sides(source_blocks(), unbalanced.ids, unbalanced.most):
        part = boundary_sums(u.T, v.T, np.ones(u.shape[1], dtype=np.int64), origin)
        total = [x + y for x, y in zip(total, part)]
    return total
