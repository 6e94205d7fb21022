"""Holes of no area: a T-junction closed by splitting the face across it.

A sliver face whose corners are collinear (a "cap": one corner on the segment of the other
two) bounds nothing, and the ``degenerate`` step removes it. What it leaves is a hole of no
area: the long edge ``e1 e2`` of the face on one side, and on the other side the chain of
shorter edges ``e2 … e1`` through the corners lying on it. No triangle of the loop's own
corners fills it (every one would be degenerate); splitting the face across the long edge at
those corners does, exactly: the face ``(e1, e2, x)`` becomes ``(e1, p1, x), (p1, p2, x), …,
(pk, e2, x)``, which cover the same triangle, wound the same way, and whose new sides are the
chain's own edges. Nothing moves and no volume changes; the face split is named in the report.

The split is made only when it is unambiguous: every corner of the loop on one line (decided
exactly), the chain running monotonically from one end of the long edge to the other, the long
edge's face owning no other side of the loop, and no new edge ``(p_i, x)`` one the mesh already
has.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np


def collinear(points: np.ndarray) -> bool:
    """Whether the points ``(k, 3)`` lie on one line, exactly."""
    p = [[Fraction(float(x)) for x in row] for row in np.asarray(points, dtype=np.float64)]
    a = p[0]
    b = next((q for q in p[1:] if q != a), None)
    if b is None:
        return True
    d = [b[i] - a[i] for i in range(3)]
    for q in p[2:]:
        e = [q[i] - a[i] for i in range(3)]
        if any(d[i] * e[j] - d[j] * e[i] for i, j in ((0, 1), (1, 2), (2, 0))):
            return False
    return True


def junction_split(points: np.ndarray, faces: np.ndarray, loop_vertices: np.ndarray, loop_faces: np.ndarray,
                   has_edge) -> tuple[int, np.ndarray] | None:
    """The split that closes a hole of no area, or None.

    Parameters
    ----------
    points : (m, 3)
        Coordinates by vertex id.
    faces : (k, 3) int
        The draft's faces, in their current winding.
    loop_vertices : (s,) int
        The hole's corners, in its winding: side ``i`` runs from corner ``i`` to ``i + 1``.
    loop_faces : (s,) int
        The face owning each side (its own side runs the other way).
    has_edge : callable
        ``has_edge(u, v)``: the mesh (or an earlier fill) already has the edge.

    Returns
    -------
    (face, triangles) or None
        The face to split, and the triangles ``(j, 3)`` (vertex ids) that replace it.
    """
    s = len(loop_vertices)
    if s < 3 or not collinear(np.asarray(points)[loop_vertices]):
        return None
    coords = np.asarray(np.asarray(points)[loop_vertices], dtype=np.float64)
    axis = int(np.argmax(coords.max(axis=0) - coords.min(axis=0)))
    position = coords[:, axis]
    if np.unique(position).size != s:
        return None                                  # two corners at one point: not a chain
    low, high = int(np.argmin(position)), int(np.argmax(position))
    # The long side joins the two ends: from corner i to i + 1 (in the loop's winding).
    long = next((i for i in range(s) if {i, (i + 1) % s} == {low, high}), None)
    if long is None:
        return None
    face = int(loop_faces[long])
    if np.count_nonzero(loop_faces == face) != 1:
        return None
    start = (long + 1) % s                           # the chain runs on from the long side's end
    chain = [int(loop_vertices[(start + i) % s]) for i in range(s)]
    steps = np.diff(position[[(start + i) % s for i in range(s)]])
    if not ((steps > 0).all() or (steps < 0).all()):
        return None                                  # the chain folds back
    # The face runs the long side the other way, from the chain's first corner to its last.
    corners = [int(v) for v in faces[face]]
    e_from, e_to = chain[0], chain[-1]
    if e_from not in corners or e_to not in corners:
        return None
    k = corners.index(e_from)
    if corners[(k + 1) % 3] != e_to:
        return None
    x = corners[(k + 2) % 3]
    path = chain                                     # e_from, ..., e_to along the face's side
    if any(has_edge(p, x) for p in path[1:-1]):
        return None
    triangles = np.array([[path[i], path[i + 1], x] for i in range(len(path) - 1)], dtype=np.int64)
    return face, triangles
