"""Face checks of a triangle soup: exactly zero area, and duplicate vertex sets.

Zero area is decided exactly: a face has zero area when the cross product of two of its sides
is exactly zero, that is when its three corners are collinear (or two coincide). Each
component of the cross product is a 2-D orientation determinant of the face projected on a
coordinate plane; the face certainly has non-zero area when one of them is certainly non-zero
by Shewchuk's a-priori filter (J. R. Shewchuk, "Adaptive precision floating-point arithmetic
and fast robust geometric predicates", Discrete Comput. Geom. 18, 1997, the ``orient2d``
error bound ``(3 + 16 eps) eps (|l| + |r|)``). The few faces the filter cannot decide (repeated
corners, near-collinear slivers, underflow or overflow) are decided in exact rational
arithmetic with ``fractions.Fraction`` on the input's own floats.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from p3d_cli.mesh.columns import columns

_EPS = np.finfo(np.float64).eps / 2
#: Shewchuk's ``ccwerrboundA``.
_ORIENT_BOUND = (3.0 + 16.0 * _EPS) * _EPS
#: Absolute slack for products that underflow (each off by at most half the smallest
#: subnormal); far below any representable non-zero determinant that matters.
_UNDERFLOW = 2.0 ** -1060


def zero_area_faces(cols: np.ndarray) -> np.ndarray:
    """Indices (ascending) of the faces of a block whose area is exactly zero.

    Parameters
    ----------
    cols : (3, 3, k) float64
        Vertex slot, axis, face (widened exactly from the input).
    """
    undecided = np.arange(cols.shape[2])
    # Overflow gives inf or nan, which no bound certifies: those faces are done exactly.
    with np.errstate(over="ignore", invalid="ignore"):
        for i, j in ((0, 1), (1, 2), (2, 0)):
            # Each plane only for the faces the planes before left undecided: a face is
            # certain when any plane certifies it, whatever the order.
            a, b, c = (cols[k][:, undecided] if undecided.size < cols.shape[2] else cols[k]
                       for k in range(3))
            # orient2d(a, b, c) on the (i, j) plane: (a_i - c_i)(b_j - c_j) - (a_j - c_j)(b_i - c_i)
            left = (a[i] - c[i]) * (b[j] - c[j])
            right = (a[j] - c[j]) * (b[i] - c[i])
            bound = _ORIENT_BOUND * (np.abs(left) + np.abs(right)) + _UNDERFLOW
            undecided = undecided[~(np.abs(left - right) > bound)]
            if undecided.size == 0:
                return undecided
    return _decided(cols, undecided)


def zero_area_faces_compiled(block: np.ndarray, kernels) -> np.ndarray:
    """``zero_area_faces`` of a ``(k, 3, 3)`` block the kernels read as it is (``kernels.takes``):
    the same float filter in one compiled pass over the block's own records, and the exact test
    on the float64 columns of the few faces it leaves (none in most meshes)."""
    undecided = np.empty(len(block), dtype=np.int64)
    count = kernels.area_filter(block, undecided)
    if count == 0:
        return undecided[:0]
    undecided = undecided[:count]
    return undecided[_decided(columns(block[undecided]), np.arange(count))]


def _decided(cols: np.ndarray, undecided: np.ndarray) -> np.ndarray:
    """The faces among ``undecided`` (ascending) of exactly zero area, by the exact tests."""
    zero, rest = exactly_zero_area(cols[:, :, undecided])
    # What the vectorised test cannot decide (coordinates beyond 2**±400, or an expansion that
    # did not settle): one face at a time in rationals. None in any mesh seen so far.
    slow = [f for f in undecided[rest].tolist() if _exact_zero_area(cols[:, :, f])]
    return np.sort(np.concatenate([undecided[zero], np.array(slow, dtype=np.int64)])).astype(np.int64)


#: Coordinates within [2**-LIMIT, 2**LIMIT] in magnitude (or 0): their differences, split
#: exactly by ``two_sum``, have products that ``two_product`` splits exactly too (no overflow,
#: and no partial product below 2**-969, where the splitting would lose bits).
_LIMIT = 2.0 ** 400
#: Distillation passes before a face is left to the rational test.
_PASSES = 24


def exactly_zero_area(cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The exact zero-area test of ``_exact_zero_area``, vectorised over the faces.

    A face has zero area when two corners coincide (two equal coordinate triples: the
    repeated-corner faces, decided at once) or when the orientation determinant of its
    projection on each coordinate plane is exactly zero. Each determinant
    ``(a_i - c_i)(b_j - c_j) - (a_j - c_j)(b_i - c_i)`` is written exactly as 16 floats
    (each difference as the two parts of ``two_sum``, each product of parts as the two of
    ``two_product``), and its sign found by distilling them with passes of error-free sums
    (Ogita, Rump and Oishi's VecSum) until nothing changes: then the last float is zero
    exactly when the sum is.

    Parameters
    ----------
    cols : (3, 3, k) float64
        Vertex slot, axis, face.

    Returns
    -------
    zero : (k,) bool
        Decided: zero area.
    undecided : (k,) bool
        Left to the rational test (coordinates out of the exact range; never both).
    """
    from p3d_cli.geometry.expansions import two_product, two_sum

    a, b, c = cols
    k = cols.shape[2]
    coincide = (a == b).all(axis=0) | (b == c).all(axis=0) | (c == a).all(axis=0)
    magnitude = np.abs(cols.reshape(9, k))
    with np.errstate(invalid="ignore"):
        in_range = (magnitude <= _LIMIT).all(axis=0) & ((magnitude == 0) | (magnitude >= 1 / _LIMIT)).all(axis=0)
    todo = np.flatnonzero(~coincide & in_range)
    zero = coincide.copy()
    undecided = ~coincide & ~in_range
    if todo.size == 0:
        return zero, undecided
    a, b, c = a[:, todo], b[:, todo], c[:, todo]
    flat = np.ones(todo.size, dtype=bool)
    settled = np.ones(todo.size, dtype=bool)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        parts = []
        for (x, y), sign in ((((a[i], c[i]), (b[j], c[j])), 1.0), (((a[j], c[j]), (b[i], c[i])), -1.0)):
            xh, xl = two_sum(x[0], -x[1])
            yh, yl = two_sum(y[0], -y[1])
            for p, q in ((xh, yh), (xh, yl), (xl, yh), (xl, yl)):
                hi, lo = two_product(p, q)
                parts += [sign * hi, sign * lo]
        terms = np.array(parts)                                # (16, faces)
        for _ in range(_PASSES):
            before = terms.copy()
            for n in range(1, terms.shape[0]):
                terms[n], terms[n - 1] = two_sum(terms[n], terms[n - 1])
            if np.array_equal(terms, before):
                break
        else:
            settled &= (terms == before).all(axis=0)
        flat &= terms[-1] == 0
    zero[todo] = flat & settled
    undecided[todo] = ~settled
    return zero, undecided


def _exact_zero_area(corners: np.ndarray) -> bool:
    """Exact test of one face ``(3, 3)`` (slot, axis): is ``(b - a) × (c - a)`` zero?"""
    a, b, c = ([Fraction(float(x)) for x in corners[k]] for k in range(3))
    e1 = [b[k] - a[k] for k in range(3)]
    e2 = [c[k] - a[k] for k in range(3)]
    return all(e1[i] * e2[j] == e1[j] * e2[i] for i, j in ((0, 1), (1, 2), (2, 0)))


def repeated_vertex_faces(ids: np.ndarray) -> np.ndarray:
    """Faces (ascending) two of whose corners are the same vertex. ``ids`` is ``(n, 3)``."""
    return np.flatnonzero((ids[:, 0] == ids[:, 1]) | (ids[:, 1] == ids[:, 2]) | (ids[:, 2] == ids[:, 0]))


def duplicate_faces(ids: np.ndarray, candidates: np.ndarray | None = None) -> np.ndarray:
    """Faces with the same three vertices as an earlier face, in any order or orientation.

    Parameters
    ----------
    ids : (n, 3) int
        Vertex ids of each face's corners.
    candidates : (c,) int, ascending, optional
        The only faces that can be duplicates (default: all).

    Returns
    -------
    (k, 2) int64
        ``(first face, later duplicate)`` rows, ordered by the later face.
    """
    faces = np.arange(len(ids)) if candidates is None else np.asarray(candidates, dtype=np.int64)
    if faces.size < 2:
        return np.zeros((0, 2), dtype=np.int64)
    key = np.sort(ids[faces], axis=1)
    order = np.lexsort((faces, key[:, 2], key[:, 1], key[:, 0]))
    sorted_key = key[order]
    new_group = np.ones(faces.size, dtype=bool)
    new_group[1:] = (sorted_key[1:] != sorted_key[:-1]).any(axis=1)
    first_of_group = order[np.flatnonzero(new_group)]
    group = np.cumsum(new_group) - 1
    dup = np.flatnonzero(~new_group)
    if dup.size == 0:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = np.stack([faces[first_of_group[group[dup]]], faces[order[dup]]], axis=1)
    return pairs[np.argsort(pairs[:, 1], kind="stable")].astype(np.int64)


def duplicate_candidates(n: int, side: np.ndarray, starts: np.ndarray, counts: np.ndarray,
                         repeated: np.ndarray) -> np.ndarray:
    """Faces (ascending) that can have a duplicate; ``duplicate_faces`` needs look at no other.

    A face with three distinct vertices and a duplicate shares all three edges with it, so
    each of its edges is used at least twice; when all three are used exactly twice, the face
    across every one of them is the duplicate, the same face three times. So a face is a
    candidate only when it has a repeated vertex, or an edge used three or more times, or
    three edges used twice with one and the same face across them.

    Parameters
    ----------
    side, starts, counts
        The sorted sides (``3 f + k``) and their edge groups (``edges.Edges``).
    repeated : (r,) int
        Faces with a repeated vertex.
    """
    candidate = np.zeros(n, dtype=bool)
    candidate[repeated] = True
    # across[3 f + k]: the face across side k of face f when that edge is used twice, else
    # -1; then a face is a candidate when the same face is across all three sides.
    across = np.full(3 * n, -1, dtype=np.int64 if n >= 2**31 else np.int32)
    step = 1 << 16
    for lo in range(0, starts.size, step):
        group_counts = counts[lo:lo + step]
        group_starts = starts[lo:lo + step].astype(np.int64)
        crowded = group_starts[group_counts > 2]
        if crowded.size:
            sizes = group_counts[group_counts > 2].astype(np.int64)
            offsets = np.arange(sizes.sum()) - np.repeat(np.cumsum(sizes) - sizes, sizes)
            candidate[side[np.repeat(crowded, sizes) + offsets] // 3] = True
        first = group_starts[group_counts == 2]
        s1, s2 = side[first].astype(np.int64), side[first + 1].astype(np.int64)
        across[s1], across[s2] = s2 // 3, s1 // 3
    across = across.reshape(n, 3)  # type: ignore[assignment]  # the list becomes its array
    candidate |= (across[:, 0] >= 0) & (across[:, 0] == across[:, 1]) & (across[:, 1] == across[:, 2])
    return np.flatnonzero(candidate)
