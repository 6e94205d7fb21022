"""Sides of ``p3d check``'s fast path paired by their exact end points (``p3d_cli.mesh.paired``).

The fast path groups sides by hashed edge keys. Where keys collide (a group of more than two
sides, or of two running the same way), those few sides are read again and grouped by their
exact end points: each exact edge must be used once each way (or, where boundary edges are
allowed, once), else the mesh takes the general path.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.closed import _lex_less
from p3d_cli.mesh.edges import corner_slot
from p3d_cli.mesh.vertices import corner_coords

#: Offsets from corner ``3 f + k`` to the next corner of face ``f``, by ``k``.
_NEXT = np.array([1, 1, -2], dtype=np.int64)


def exact_twins(blocks, sides: np.ndarray):
    """Pair sides by their exact end points: ``(a, b)`` with side ``b`` running back along
    side ``a``; None when some exact edge is not used once each way."""
    ends = sides + _NEXT[corner_slot(sides)]
    coords = corner_coords(blocks, np.concatenate([sides, ends]))
    start, end = coords[:sides.size], coords[sides.size:]
    # Each undirected edge as (lower point, higher point) in lexicographic order.
    lo_first = _lex_less(start, end)
    lo = np.where(lo_first[:, None], start, end)
    hi = np.where(lo_first[:, None], end, start)
    order = np.lexsort((~lo_first, hi[:, 2], hi[:, 1], hi[:, 0], lo[:, 2], lo[:, 1], lo[:, 0]))
    if order.size % 2:
        return None
    a, b = order[0::2], order[1::2]
    same = (lo[a] == lo[b]).all(axis=1) & (hi[a] == hi[b]).all(axis=1)
    if not (same.all() and lo_first[a].all() and not lo_first[b].any()):
        return None
    # Sorted, a third use of an edge would meet its pair's edge in the next pair.
    if a.size > 1 and ((lo[a[1:]] == lo[a[:-1]]).all(axis=1) & (hi[a[1:]] == hi[a[:-1]]).all(axis=1)).any():
        return None
    return sides[a], sides[b]


def exact_edges(blocks, sides: np.ndarray):
    """``exact_twins`` where an exact edge may also be used once: ``(a, b, lone)``, the twin
    sides and the boundary sides; None when some exact edge is used otherwise."""
    coords = corner_coords(blocks, np.concatenate([sides, sides + _NEXT[corner_slot(sides)]]))
    start, end = coords[:sides.size], coords[sides.size:]
    lo_first = _lex_less(start, end)
    lo = np.where(lo_first[:, None], start, end)
    hi = np.where(lo_first[:, None], end, start)
    order = np.lexsort((~lo_first, hi[:, 2], hi[:, 1], hi[:, 0], lo[:, 2], lo[:, 1], lo[:, 0]))
    lo, hi, lo_first, sides = lo[order], hi[order], lo_first[order], sides[order]
    new = np.ones(sides.size, dtype=bool)
    new[1:] = (lo[1:] != lo[:-1]).any(axis=1) | (hi[1:] != hi[:-1]).any(axis=1)
    at = np.flatnonzero(new)
    sizes = np.diff(np.append(at, sides.size))
    pairs = at[sizes == 2]
    if (sizes > 2).any() or not (lo_first[pairs].all() and not lo_first[pairs + 1].any()):
        return None
    return sides[pairs], sides[pairs + 1], sides[at[sizes == 1]]

