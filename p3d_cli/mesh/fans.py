"""Non-manifold vertices: vertices whose faces form more than one fan.

Corners at the same vertex belong to one fan when their faces meet across an edge used by
exactly two faces, or when they are two corners of one face (a repeated vertex). A manifold
vertex has one fan; two solids touching at a point have two there.

Fast path. Around a *clean* vertex (every edge at it used once each way by two faces, no face
with a repeated vertex at it, no point face) the corners form cycles: from corner ``c`` (whose
side runs ``v -> w``), the twin side ``w -> v`` ends at the next corner of the fan, so
``c -> next(twin(c))`` is a permutation of the vertex's corners whose cycles are its fans. The
vertex is manifold when the cycle through its first corner has all ``k`` corners: one walk per
vertex, all vertices walked together, ``sum k = 3n`` steps in all. Every other vertex (open,
non-manifold or misoriented edges, repeated corners, or a fan longer than ``WALK`` corners)
takes the general path: a union-find over its corners only.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.edges import _PREVIOUS, Edges, corner_slot, next_corner
from p3d_cli.mesh.shells import roots

#: Fans walked step by step (one vectorised step per corner); longer ones use the union-find.
WALK = 64
#: Faces listed per non-manifold vertex sample.
SAMPLE_FACES = 8


def nonmanifold_vertices(ids: np.ndarray, m: int, first_corner: np.ndarray, degree: np.ndarray,
                         edges: Edges) -> np.ndarray:
    """Ids (ascending) of the non-manifold vertices not on a non-manifold edge.

    Parameters
    ----------
    ids : (3n,) int
        Vertex id of each corner.
    m : int
        Number of vertices.
    first_corner, degree : (m,) int
        Each vertex's first corner (file order) and its number of corners.
    edges : Edges
    """
    n = ids.size // 3
    faces = ids.reshape(n, 3)
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
    unclean = np.zeros(m, dtype=bool)
    unclean[faces[repeated].reshape(-1)] = True
    clean_pair = np.zeros(edges.count, dtype=bool)
    clean_pair[edges.counts == 2] = True
    clean_pair[edges.misoriented] = False
    _mark_ends(unclean, ids, edges, ~clean_pair)
    on_bad_edge = np.zeros(m, dtype=bool)
    if edges.nonmanifold.size:
        _mark_ends(on_bad_edge, ids, edges, edges.counts > 2)
    twin = _twins(ids.size, edges, clean_pair)
    walked = _walk(ids, first_corner, degree, twin, ~unclean)
    unclean |= walked == 0          # walks longer than WALK: general path
    short = (walked > 0) & (walked < degree)
    fans = _general_fans(ids, faces, repeated, edges, unclean, twin) if unclean.any() else None
    bad = short if fans is None else short | ((fans > 1) & ~on_bad_edge)
    return np.flatnonzero(bad)


def _mark_ends(mark: np.ndarray, ids: np.ndarray, edges: Edges, groups: np.ndarray) -> None:
    """Mark both end vertices of every side of the selected edge groups."""
    sides = edges.side[np.repeat(groups, edges.counts)]
    mark[ids[sides]] = True
    mark[ids[next_corner(sides.astype(np.int64))]] = True


def _walk(ids, first_corner, degree, twin: np.ndarray, clean) -> np.ndarray:
    """Length of the fan cycle through each clean vertex's first corner (0: not walked)."""
    length = np.zeros(first_corner.size, dtype=np.int32)
    vertices = np.flatnonzero(clean)
    if vertices.size == 0:
        return length
    # In slices of vertices, so that the walk's temporaries stay small beside the corners.
    for lo in range(0, vertices.size, 1 << 16):
        _walk_some(twin, first_corner, vertices[lo:lo + (1 << 16)], length)
    return length


def _walk_some(twin, first_corner, vertices, length) -> None:
    start = first_corner[vertices].astype(np.int64)
    current = start
    for step in range(1, WALK + 1):
        current = next_corner(twin[current].astype(np.int64))
        back = current == start
        if back.any():              # most vertices come back together: compress rarely
            length[vertices[back]] = step
            keep = ~back
            vertices, start, current = vertices[keep], start[keep], current[keep]
            if vertices.size == 0:
                return


def _twins(size: int, edges: Edges, clean_pair: np.ndarray) -> np.ndarray:
    """``twin[s]``: the other side of side ``s``'s edge, for the clean pairs (-1 elsewhere)."""
    if edges.spare is not None and edges.spare.size == size:
        twin = edges.spare
        twin[:] = -1
    else:
        twin = np.full(size, -1, dtype=np.int32 if size < 2**31 else np.int64)
    side, step = edges.side, 1 << 16
    if side.size == 2 * edges.count and clean_pair.all():     # closed: pairs are adjacent
        for lo in range(0, side.size, 2 * step):
            pair = side[lo:lo + 2 * step].astype(np.int64)
            twin[pair[0::2]] = pair[1::2]
            twin[pair[1::2]] = pair[0::2]
        return twin
    starts = edges.starts[clean_pair].astype(np.int64)
    for lo in range(0, starts.size, step):
        first = starts[lo:lo + step]
        a, b = side[first].astype(np.int64), side[first + 1].astype(np.int64)
        twin[a], twin[b] = b, a
    return twin


def _general_fans(ids, faces, repeated, edges: Edges, selected: np.ndarray, twin: np.ndarray) -> np.ndarray:
    """Fans per vertex (for the ``selected`` vertices; 0 elsewhere), by union-find on the
    corners at those vertices only (so an open mesh with a few boundary vertices pays for a
    few corners, not for all of them).

    Two corners at a vertex are joined when their faces share an edge used by exactly two
    faces there. For the clean pairs, each selected corner's two sides (the one leaving it and
    the one arriving at it) lead to their twins (``twin``); the misoriented pairs, which have
    no twin there, are read from their groups."""
    point_face = (faces[:, 0] == faces[:, 1]) & (faces[:, 1] == faces[:, 2])
    # Corners of faces with three equal corners touch nothing: leave them out of the count.
    corners = np.flatnonzero(selected[ids] & ~np.repeat(point_face, 3))
    if corners.size == 0:
        return np.zeros(selected.size, dtype=np.int64)
    a, b = [], []
    for lo in range(0, corners.size, 1 << 16):
        at = corners[lo:lo + (1 << 16)]
        vertex = ids[at]
        for side in (at, at + _PREVIOUS[corner_slot(at)]):
            other = twin[side].astype(np.int64)
            paired = other >= 0
            other = other[paired]
            a.append(at[paired])    # either side's corner at the vertex is the selected corner
            b.append(np.where(ids[other] == vertex[paired], other, next_corner(other)))
    pair_start = edges.misoriented
    for lo in range(0, pair_start.size, 1 << 16):
        first = edges.starts[pair_start[lo:lo + (1 << 16)]].astype(np.int64)
        s1, s2 = edges.side[first].astype(np.int64), edges.side[first + 1].astype(np.int64)
        for end in (ids[s1], ids[next_corner(s1)]):   # the edge's two vertices
            keep = selected[end]
            x1, x2, vertex = s1[keep], s2[keep], end[keep]
            # A side runs from its own corner to the next one: take the corner at `vertex`.
            a.append(np.where(ids[x1] == vertex, x1, next_corner(x1)))
            b.append(np.where(ids[x2] == vertex, x2, next_corner(x2)))
    twins = np.flatnonzero(repeated & ~point_face)
    for i, j in ((0, 1), (1, 2), (2, 0)):
        same = twins[(faces[twins, i] == faces[twins, j]) & selected[faces[twins, i]]]
        a.append(3 * same + i)
        b.append(3 * same + j)
    a, b = np.concatenate(a), np.concatenate(b)  # type: ignore[assignment]  # the list becomes its array
    chosen = np.zeros(ids.size, dtype=bool)     # np.isin's sort of a and b, as a lookup
    chosen[corners] = True
    live = chosen[a] & chosen[b]
    del chosen
    parent = roots(corners.size, np.searchsorted(corners, a[live]), np.searchsorted(corners, b[live]))
    fan_roots = corners[parent == np.arange(corners.size)]
    return np.bincount(ids[fan_roots], minlength=selected.size)


def vertex_sample_faces(ids: np.ndarray, vertex: int) -> tuple[int, ...]:
    """Up to ``SAMPLE_FACES`` faces (ascending) with a live corner at ``vertex``."""
    n = ids.size // 3
    faces = ids.reshape(n, 3)
    point_face = (faces[:, 0] == faces[:, 1]) & (faces[:, 1] == faces[:, 2])
    hits = np.unique(np.flatnonzero(ids == vertex) // 3)
    hits = hits[~point_face[hits]]
    return tuple(int(f) for f in hits[:SAMPLE_FACES])
