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
and the fast path's safety net.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from p3d_cli.mesh.boundary_terms import InexactLocal, Locals, WorldCross, combine, combine_bound, frame_origin
from p3d_cli.mesh.closed import (_lex_less, column_edge_keys, key_groups, side_keys, sides_of_edges)
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.kernels import compiled, sort, takes
from p3d_cli.mesh.splitmix import mix

#: Sides handled per vectorised step of the boundary terms: the temporaries (~30 rows of this
#: many floats) stay in cache; 2**15 was 1.7x slower, 2**13 the same (a 1M-face soup).
SIDE_BLOCK = 1 << 14


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


@dataclass(frozen=True)
class Unbalanced:
    """The edges of sorted side keys whose two directions are not used equally often.

    Attributes
    ----------
    ids : (d,) uint64, sorted
        Their edge ids (``key >> 1``). Equal exact edges have equal keys, so an edge whose key
        group is balanced cancels unless two different edges' 64-bit keys collided (the risk
        ``closed`` already takes for its pairs).
    edges : int
        The net boundary's size: ``|forward - backward|`` summed over their key groups.
    sides : int
        Sides in their key groups.
    total : int
        All the sides.
    """

    ids: np.ndarray
    edges: int
    sides: int
    total: int

    @property
    def most(self) -> bool:
        """Whether most sides are in unbalanced groups (a soup): then every side is used."""
        return 2 * self.sides > self.total


def unbalanced_groups(keys: np.ndarray) -> Unbalanced:
    """``Unbalanced`` of sorted side ``keys``, in one scan."""
    kernels = compiled()
    if kernels is not None and keys.flags.c_contiguous:
        ids, size, sides, _ = kernels.groups(keys)
        return Unbalanced(np.frombuffer(ids, dtype=np.uint64).copy(), size, sides, int(keys.size))
    found, size, sides = [], 0, 0
    for edge, counts, forward in key_groups(keys):
        net = 2 * forward.astype(np.int64) - counts
        odd = net != 0
        found.append(edge[odd])
        size += int(np.abs(net[odd]).sum())
        sides += int(counts[odd].sum())
    return Unbalanced(np.concatenate(found) if found else keys[:0], size, sides, int(keys.size))


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


def unbalanced_of(source_blocks) -> Unbalanced:
    """``unbalanced_groups`` of the triangles read once from ``source_blocks()`` (a callable)."""
    keys = [column_edge_keys(columns(block)) for block in source_blocks()]
    flat = np.concatenate(keys) if keys else np.zeros(0, dtype=np.uint64)
    sort(flat)  # radix, when compiled: the same order
    return unbalanced_groups(flat)


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


def unbalanced_sides(source_blocks, unbalanced: np.ndarray, every: bool = False):
    """Every side (as ``(3, k)`` start and end columns, ``-0.0`` read as ``0.0``) whose edge
    is in ``unbalanced`` (or every side with two distinct ends, if ``every``), ``SIDE_BLOCK``
    at most at a time, from one more pass.

    These sides are the net boundary plus sides that cancel in pairs (``u→v`` and ``v→u``):
    as a chain they are the net boundary, a cycle, which is all ``boundary_terms`` needs, and
    the terms of a pair cancel (exactly: ``Locals`` computes ``v→u``'s as the negated bits of
    ``u→v``'s, but for the order of the low parts' sum, within its bound). Membership is a
    binary search in the sorted ids, not ``numpy.isin`` (which hashes all the ids again for
    every block); a soup, whose sides are nearly all unbalanced, skips it (``every``).
    """
    ids = np.sort(unbalanced)
    if ids.size == 0:
        return
    members = _Members(ids)
    kernels = compiled()
    out = np.empty((0, 6))
    index = members.starts() if kernels is not None and not every else None
    for block in source_blocks:
        if kernels is not None and not every and takes(block):
            # The same sides in the same order, picked by the compiled kernel from the
            # block's own records (no float64 copy, no keys array).
            if out.shape[0] < 3 * len(block):
                out = np.empty((3 * len(block), 6))
            sides = out[:kernels.pick_sides(block, ids, members.bits, int(members.shift), *index, out)]
            for first in range(0, sides.shape[0], SIDE_BLOCK):
                chunk = sides[first:first + SIDE_BLOCK]
                yield np.ascontiguousarray(chunk[:, :3].T), np.ascontiguousarray(chunk[:, 3:].T)
            continue
        cols = columns(block)
        if cols.shape[2] == 0:
            continue
        keys, keep = side_keys(cols)
        if not every:
            hit = members(keys >> np.uint64(1))
            if not hit.any():
                continue
            # Only the hit sides' corners, in the keys' (slot, face) order: side i of the kept
            # sides is slot i // k, face i % k (a few per cent of the sides on a holed mesh).
            position = np.flatnonzero(hit)
            if keep is not None:
                position = np.flatnonzero(keep.reshape(-1))[position]
            slot, face = np.divmod(position, cols.shape[2])
            start = cols[slot, :, face] + 0.0
            end = cols[(slot + 1) % 3, :, face] + 0.0
            for first in range(0, start.shape[0], SIDE_BLOCK):
                at = slice(first, first + SIDE_BLOCK)
                yield np.ascontiguousarray(start[at].T), np.ascontiguousarray(end[at].T)
            continue
        corners = np.moveaxis(cols, 1, 2) + 0.0            # (slot, face, axis), as keys
        start, end = corners, corners[[1, 2, 0]]
        if keep is not None:
            start, end = start[keep], end[keep]
        start, end = start.reshape(-1, 3), end.reshape(-1, 3)
        for first in range(0, start.shape[0], SIDE_BLOCK):
            at = slice(first, first + SIDE_BLOCK)
            yield np.ascontiguousarray(start[at].T), np.ascontiguousarray(end[at].T)


class _Members:
    """``numpy.isin(edge, ids)`` for sorted ``ids`` of edges (63-bit hashes): a few equality
    tests when there are a few ids (a mesh with a hole or two: 12x faster than a binary
    search), else a table of the ids' top bits first, which turns most edges away with one
    lookup, and a binary search for the rest. (A binary search of every edge took 0.5 s of a
    1M-face mesh with 1 % of its faces missing, 30,000 ids: three times the whole analysis.)"""

    def __init__(self, ids: np.ndarray, width: int = 63) -> None:
        self.ids = ids
        #: The ids' width in bits: 63 for edge ids, more or less for other ids (print ids).
        self.width = width
        # About 32 slots an id (at most 2^24): 97 % of the other edges miss the table.
        bits = min(24, max(8, (32 * ids.size).bit_length()))
        self.shift = np.uint64(width - bits)
        self.table = np.zeros(1 << bits, dtype=bool)
        self.table[(ids >> self.shift).astype(np.intp)] = True
        #: The table packed 8 slots a byte, for the compiled ``pick_sides``.
        self.bits = np.packbits(self.table, bitorder="little")

    def starts(self) -> tuple[np.ndarray, int]:
        """An index of the ids by their top bits, for the compiled ``pick_sides``: ``starts[j]``
        is the first id at or above ``j << shift``, about one id a slot; and ``shift``."""
        bits = max(1, int(self.ids.size).bit_length())
        shift = self.width - bits
        bounds = np.arange((1 << bits) + 1, dtype=np.uint64) << np.uint64(shift)
        return np.searchsorted(self.ids, bounds).astype(np.int64), shift

    def __call__(self, edge: np.ndarray) -> np.ndarray:
        ids = self.ids
        if ids.size <= 16:
            hit = edge == ids[0]
            for value in ids[1:]:
                hit |= edge == value
            return hit
        hit = self.table[(edge >> self.shift).astype(np.intp)]
        maybe = np.flatnonzero(hit)
        candidates = edge[maybe]
        at = np.minimum(np.searchsorted(ids, candidates), ids.size - 1)
        hit[maybe] = ids[at] == candidates
        return hit


def sides_of_prints(source_blocks, prints: np.ndarray, low: int, count: int, balance: int,
                    total: int) -> tuple[Unbalanced, list[np.ndarray]] | None:
    """``unbalanced_groups`` of every side's key and ``unbalanced_sides``' sides, block by
    block, from one pass that picks the sides whose print id (``key >> low``) is in ``prints``
    (the compiled ``print_groups``' answers: ``count`` sides) with their keys.

    Every edge's sides share a print id, so the picked sides hold whole edge groups; their keys
    sorted give the unbalanced edges among them exactly. Those are all the mesh's when the
    balance of the picked sides, ``Σ ±mix(key | 1)`` (+ forward, - backward) mod 2**64, is the
    whole mesh's ``balance``: an unbalanced edge left out (two of them cancelling in one print
    group) would be missing from it but for a 64-bit coincidence, as in the closed test
    (``p3d_cli.mesh.kernels.ForwardBuckets``). Returns None, for the caller's other road, when it
    is not, when no edge is unbalanced, or when a block is not one the kernels read.

    Returns
    -------
    unbalanced : Unbalanced
        As ``unbalanced_groups`` of every side's key (``total`` sides).
    sides : list of (m, 6) float64
        Each block's sides whose edge is unbalanced, as the compiled ``unbalanced_sides`` picks
        them (start, end; the same order).
    """
    kernels = compiled()
    if kernels is None or prints.size == 0:
        return None
    members = _Members(prints, 64 - low)
    index = members.starts()
    picked: list[np.ndarray] = []
    keys: list[np.ndarray] = []
    out = np.empty((0, 6))
    made = np.empty(0, dtype=np.uint64)
    found = 0
    for block in source_blocks:
        if not takes(block):
            return None
        if out.shape[0] < 3 * len(block):
            out, made = np.empty((3 * len(block), 6)), np.empty(3 * len(block), dtype=np.uint64)
        n = kernels.pick_sides(block, prints, members.bits, int(members.shift), *index, out, low, made)
        found += n
        if found > count:
            return None
        picked.append(out[:n].copy())
        keys.append(made[:n].copy())
    every = np.concatenate(keys) if keys else np.zeros(0, dtype=np.uint64)
    if every.size != count:
        return None
    g = mix(every | np.uint64(1))
    forward = (every & np.uint64(1)).astype(bool)
    if (int(g[forward].sum(dtype=np.uint64)) - int(g[~forward].sum(dtype=np.uint64)) - balance) % (1 << 64):
        return None
    ordered = every.copy()
    sort(ordered)
    ids, size, sides, doubtful = kernels.groups(ordered)
    if doubtful is not None or not ids:
        return None
    unbalanced = Unbalanced(np.frombuffer(ids, dtype=np.uint64).copy(), size, sides, total)
    if sides == count:                      # every picked side is on an unbalanced edge
        return unbalanced, picked
    hit = _Members(unbalanced.ids)(every >> np.uint64(1))
    ends = np.cumsum([k.size for k in keys])
    return unbalanced, [p[h] for p, h in zip(picked, np.split(hit, ends[:-1]))]


def block_sides(picked: list[np.ndarray]):
    """``unbalanced_sides``' chunks of sides already picked block by block (``sides_of_prints``)."""
    for sides in picked:
        for first in range(0, sides.shape[0], SIDE_BLOCK):
            chunk = sides[first:first + SIDE_BLOCK]
            yield np.ascontiguousarray(chunk[:, :3].T), np.ascontiguousarray(chunk[:, 3:].T)


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
