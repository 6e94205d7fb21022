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
its accurate local sums plus a few boundary terms, which are computed here in exact integer
arithmetic (every float64 is an integer times a power of two).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from p3d_cli.mesh.closed import _lex_less, column_edge_keys, key_groups, sides_of_edges


#: Above this many net boundary sides the exact terms would cost more than the float sums
#: about the world origin (a soup of disconnected faces is all boundary); the caller falls
#: back to those, whose rounding bound says how accurate they are.
EXACT_LIMIT = 1 << 16


def unbalanced_edges(keys: np.ndarray) -> np.ndarray:
    """Edge ids (``key >> 1``) whose two directions are not used equally often.

    Parameters
    ----------
    keys : (m,) uint64, sorted
        Directed edge keys (``closed.column_edge_keys``).

    Notes
    -----
    Equal exact edges have equal keys, so an edge whose key group is balanced cancels unless
    two different edges' 64-bit keys collided (the risk ``closed`` already takes for its pairs).
    """
    found = [edge[2 * forward != counts] for edge, counts, forward in key_groups(keys)]
    return np.concatenate(found) if found else keys[:0]


def net_boundary(source_blocks, unbalanced: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The net boundary's distinct directed edges ``u→v`` with their multiplicities.

    Parameters
    ----------
    source_blocks : iterable of (k, 3, 3) arrays
        The triangles, in blocks (read once more).
    unbalanced : (d,) uint64
        From ``unbalanced_edges``.

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
    from p3d_cli.mesh.integrals import columns

    keys = [column_edge_keys(columns(block)) for block in source_blocks()]
    flat = np.concatenate(keys) if keys else np.zeros(0, dtype=np.uint64)
    flat.sort()
    return net_boundary(source_blocks(), unbalanced_edges(flat))


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
