"""The faces near given faces: a box tree of all the faces, walked by each given triangle.

Filling a hole adds faces that must cross no other face (``p3d_cli.repairs.solidity``). The
exact pair test only needs, for each new face, the faces that could touch it: the faces whose
box meets the new *triangle*. A box around the new face would do for a small, compact face,
but the filling of a long loop is a fan of slivers whose boxes span the whole hole and meet
most of the mesh, while the slivers themselves pass near few faces.

So the other faces go into a tree of boxes (a bounding volume hierarchy, C. Ericson,
*Real-Time Collision Detection*, Morgan Kaufmann 2005, ch. 6): sorted along a Morton curve of
their boxes' centres (G. M. Morton, IBM technical report, 1966), cut into leaves of ``LEAF``
consecutive faces, and joined two by two up to one root. Every new triangle walks down from
the root into the nodes whose boxes it meets, and at the leaves keeps the faces whose boxes it
meets: in the compiled kernels (``near_walk``), one triangle at a time, depth first; on numpy,
``WALK`` triangles at a time, level by level (the pairs of a level held at once: ten fans of
1,000 slivers had 10 million at the leaves). Both make the same float tests, so the same pairs.

"Meets" is the separating-axis test of a triangle and a box (T. Akenine-Möller, "Fast 3D
triangle-box overlap testing", *Journal of Graphics Tools* 6(1), 2001: the box's three axes,
the triangle's normal and the nine products of a triangle edge with a box axis), in floating
point on boxes grown by ``MARGIN`` of the largest coordinate, far beyond the rounding of the
projections: a box is passed over only when the triangle is certainly clear of it, so a face
that touches a new face is never missed. The answer is a superset of the faces that can touch
a new face; which of them do is decided exactly after (``p3d_cli.mesh.intersections``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.compiled_grid import Shadow
from p3d_cli.mesh.kernels import compiled

#: Faces per leaf of the tree.
LEAF = 16
#: Bits per axis of the Morton code (a 30-bit key).
MORTON_BITS = 10
#: Boxes are grown by this fraction of the largest absolute coordinate: the projections'
#: rounding is a few units of 2**-53 of it, so a triangle and a box that touch always pass.
MARGIN = 2.0 ** -40
#: The label of a node whose faces have different labels.
MIXED = np.iinfo(np.int64).min
#: Pairs (triangle, node) tested per batch (bounded temporaries).
BATCH = 1 << 18
#: Triangles walking the tree together on the numpy road (bounds the frontier).
WALK = 1024
#: The compiled walk's first output size, in pairs (grown when one triangle's do not fit).
OUTPUTS = 1 << 16


def near_pairs(points: np.ndarray, faces: np.ndarray, query: np.ndarray,
               group: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(k, f)`` where the box of face ``f`` meets the triangle of face
    ``query[k]``: every face that touches a query face is among them, with that face.

    Parameters
    ----------
    points : (m, 3) float64
        Finite coordinates by vertex id.
    faces : (n, 3) int
        Vertex ids of every face.
    query : (k,) int
        The faces whose neighbourhoods are wanted (ids into ``faces``).
    group : (n,) int, optional
        A label per face (negative: none): a face is not paired with a query face of its own
        label, nor with itself.

    Returns
    -------
    at, face : (p,) int64
        Positions in ``query``, and face ids; sorted by position, then face.
    """
    points = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces)
    query = np.asarray(query, dtype=np.int64)
    none = np.zeros(0, dtype=np.int64)
    if query.size == 0 or len(faces) == 0:
        return none, none
    scale = float(np.abs(points).max()) if len(points) else 0.0
    margin = MARGIN * scale if scale > 0 else MARGIN
    triangles = points[faces[query]]
    inside, lo, hi = _candidates(points, faces, triangles, margin)
    # A face of the query's own label is dropped at the leaves, before the geometry: a fan's
    # faces all meet each other's boxes at its apex.
    label = np.full(len(faces), -1, dtype=np.int64) if group is None else np.asarray(group, dtype=np.int64)
    mine = np.where(label[query] >= 0, label[query], -2 - np.arange(query.size))
    theirs = label.copy()
    theirs[query] = mine
    at, position = _tree_query(triangles, lo, hi, margin, mine, theirs[inside])
    face = inside[position]
    order = np.lexsort((face, at))
    return at[order], face[order]


def _candidates(points: np.ndarray, faces: np.ndarray, triangles: np.ndarray,
                margin: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The faces that may meet a query triangle, ascending, and their exact boxes ``(c, 3)``.

    Only the faces whose boxes meet the box of all the query triangles (grown by ``margin``)
    can meet one of them; nor can any whose extent along an axis misses the union of the
    triangles' grown extents there (the walk's first test, per triangle, is this one:
    fillings in a few flat planes leave out most of a mesh the box around them all holds).
    The axes are taken one at a time, the query's narrowest (for the mesh's size) first, each
    extent made only for the faces the axes before left.
    """
    corners = np.ascontiguousarray(faces.T)
    low, high = triangles.min(axis=1) - margin, triangles.max(axis=1) + margin
    top, bottom = triangles.max(axis=(0, 1)) + margin, triangles.min(axis=(0, 1)) - margin
    span = points.max(axis=0) - points.min(axis=0)
    inside = np.arange(len(faces))
    extents: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for axis in np.argsort((top - bottom) / np.where(span > 0, span, 1.0), kind="stable").tolist():
        column = np.ascontiguousarray(points[:, axis])
        a, b, c = (column[corners[k, inside]] for k in range(3))
        lo = np.minimum(a, b)
        np.minimum(lo, c, out=lo)
        hi = np.maximum(a, b, out=a)
        np.maximum(hi, c, out=hi)
        keep = (lo <= top[axis]) & (hi >= bottom[axis])
        rows = np.flatnonzero(keep)
        shadow = Shadow(low[:, axis], high[:, axis], float(low[:, axis].min()), float(high[:, axis].max()))
        keep[rows] = shadow.meets(lo[rows], hi[rows])
        inside = inside[keep]
        extents = {k: (x[keep], y[keep]) for k, (x, y) in extents.items()}
        extents[axis] = (lo[keep], hi[keep])
    return (inside, np.stack([extents[k][0] for k in range(3)], axis=1),
            np.stack([extents[k][1] for k in range(3)], axis=1))


def _tree_query(triangles: np.ndarray, lo: np.ndarray, hi: np.ndarray, margin: float,
                mine: np.ndarray, theirs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pairs ``(triangle, box)`` of the triangles ``(k, 3, 3)`` and the boxes ``lo``/``hi``
    that meet (grown by ``margin``), but those where the triangle's label ``mine`` is the
    box's ``theirs``."""
    none = np.zeros(0, dtype=np.int64)
    if len(lo) == 0:
        return none, none
    order = np.argsort(_morton((lo + hi) / 2), kind="stable")
    lo, hi = lo[order], hi[order]
    label = theirs[order]
    levels = _levels(lo, hi, label)
    fast = compiled()
    if fast is not None:
        tri, face = _compiled_walk(fast, triangles, levels, lo, hi, label, mine, margin)
    else:
        # A block of triangles at a time: the frontier of all of them at once held 10 million
        # pairs (1 GB) for the fans of slivers of ten 1,000-edge holes.
        found = [_walk(triangles[at:at + WALK], levels, lo, hi, label, mine[at:at + WALK], margin)
                 for at in range(0, len(triangles), WALK)]
        tri = np.concatenate([t + at for (t, _), at in zip(found, range(0, len(triangles), WALK))])
        face = np.concatenate([f for _, f in found])
    return tri, order[face]


def _levels(lo: np.ndarray, hi: np.ndarray, label: np.ndarray) -> list:
    """The tree over boxes in their Morton order: ``(low, high, same)`` per level, the root
    first; node ``i`` of a level has children ``2i`` and ``2i + 1`` in the next, and leaf ``i``
    holds boxes ``LEAF i`` to ``LEAF i + LEAF - 1``. ``same`` is the one label of a node's
    boxes, else ``MIXED``: a triangle skips the nodes of its own label (its fan's faces)."""
    starts = np.arange(0, len(lo), LEAF)
    low_label, high_label = np.minimum.reduceat(label, starts), np.maximum.reduceat(label, starts)
    levels = [(np.minimum.reduceat(lo, starts, axis=0), np.maximum.reduceat(hi, starts, axis=0),
               np.where(low_label == high_label, low_label, MIXED))]
    while len(levels[-1][0]) > 1:
        low, high, same = levels[-1]
        pairs = np.arange(0, len(low), 2)
        sibling = np.minimum(pairs + 1, len(low) - 1)
        levels.append((np.minimum.reduceat(low, pairs, axis=0), np.maximum.reduceat(high, pairs, axis=0),
                       np.where(same[pairs] == same[sibling], same[pairs], MIXED)))
    levels.reverse()
    return levels


def _walk(triangles: np.ndarray, levels: list, lo: np.ndarray, hi: np.ndarray, label: np.ndarray,
          mine: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """The pairs (triangle, box position) that meet: every triangle walks down from the root,
    all at once, level by level (the frontier: the pairs whose boxes meet)."""
    tri = np.arange(len(triangles), dtype=np.int64)
    node = np.zeros(len(triangles), dtype=np.int64)
    keep = _meets(triangles, tri, levels[0][0], levels[0][1], node, margin)
    tri, node = tri[keep], node[keep]
    for low, high, same in levels[1:]:
        tri = np.repeat(tri, 2)
        node = (np.repeat(node, 2) * 2) + np.tile(np.array([0, 1]), node.size)
        real = node < len(low)
        tri, node = tri[real], node[real]
        other = same[node] != mine[tri]
        tri, node = tri[other], node[other]
        keep = _meets(triangles, tri, low, high, node, margin)
        tri, node = tri[keep], node[keep]
    # The leaves' boxes: positions leaf * LEAF + 0..LEAF-1.
    tri = np.repeat(tri, LEAF)
    face = np.repeat(node * LEAF, LEAF) + np.tile(np.arange(LEAF), node.size)
    real = face < len(lo)
    tri, face = tri[real], face[real]
    other = mine[tri] != label[face]
    tri, face = tri[other], face[other]
    keep = _meets(triangles, tri, lo, hi, face, margin)
    return tri[keep], face[keep]


def _compiled_walk(fast, triangles: np.ndarray, levels: list, lo: np.ndarray, hi: np.ndarray, label: np.ndarray,
                   mine: np.ndarray, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """``_walk`` in the compiled kernels (``near_walk``): the same pairs, the same float tests,
    one triangle at a time down the tree, into outputs grown when one triangle's pairs do not
    fit."""
    node_lo = np.ascontiguousarray(np.concatenate([low for low, _, _ in levels]), dtype=np.float64)
    node_hi = np.ascontiguousarray(np.concatenate([high for _, high, _ in levels]), dtype=np.float64)
    node_label = np.ascontiguousarray(np.concatenate([same for _, _, same in levels]), dtype=np.int64)
    offsets = np.concatenate([[0], np.cumsum([len(low) for low, _, _ in levels])]).astype(np.int64)
    corners = np.ascontiguousarray(triangles, dtype=np.float64)
    lo, hi = np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64)
    label, mine = np.ascontiguousarray(label, dtype=np.int64), np.ascontiguousarray(mine, dtype=np.int64)
    size = max(OUTPUTS, 32 * len(triangles))
    tris, faces = [], []
    start = 0
    while start < len(triangles):
        out_tri, out_face = np.empty(size, dtype=np.int64), np.empty(size, dtype=np.int64)
        after, written = fast.near_walk(corners, node_lo, node_hi, node_label, offsets, lo, hi, label, mine,
                                        margin, LEAF, start, out_tri, out_face)
        tris.append(out_tri[:written].copy())
        faces.append(out_face[:written].copy())
        if after == start:
            size *= 4               # one triangle's pairs did not fit
        start = after
    return np.concatenate(tris), np.concatenate(faces)


def _morton(centres: np.ndarray) -> np.ndarray:
    """30-bit Morton keys (``uint64``) of points quantised to their box."""
    low = centres.min(axis=0)
    span = centres.max(axis=0) - low
    span[span <= 0] = 1.0
    cells = (1 << MORTON_BITS) - 1
    q = np.clip(((centres - low) / span * cells), 0, cells).astype(np.int64)
    # Bit ``b`` of axis ``a`` goes to bit ``3 b + a``: each axis's bits spread by one table.
    key = _SPREAD[q[:, 0]]
    key |= _SPREAD[q[:, 1]] << np.uint64(1)
    key |= _SPREAD[q[:, 2]] << np.uint64(2)
    return key


def _spread() -> np.ndarray:
    """``(2**MORTON_BITS,)`` uint64: each value's bit ``b`` moved to bit ``3 b``."""
    values = np.arange(1 << MORTON_BITS, dtype=np.uint64)
    out = np.zeros(values.size, dtype=np.uint64)
    for bit in range(MORTON_BITS):
        out |= ((values >> np.uint64(bit)) & np.uint64(1)) << np.uint64(3 * bit)
    return out


_SPREAD = _spread()


def _meets(triangles: np.ndarray, tri: np.ndarray, lo: np.ndarray, hi: np.ndarray, box: np.ndarray,
           margin: float) -> np.ndarray:
    """Whether triangle ``tri[i]`` may meet box ``box[i]`` (grown by ``margin``), in batches:
    the triangle's own box first, the separating-axis test on the pairs it leaves."""
    out = np.zeros(tri.size, dtype=bool)
    low, high = triangles.min(axis=1) - margin, triangles.max(axis=1) + margin
    for at in range(0, tri.size, BATCH):
        t, b = tri[at:at + BATCH], box[at:at + BATCH]
        rows = np.flatnonzero(((low[t] <= hi[b]) & (lo[b] <= high[t])).all(axis=1))
        out[at + rows] = _triangle_meets_box(triangles[t[rows]], lo[b[rows]], hi[b[rows]], margin)
    return out


def _triangle_meets_box(corners: np.ndarray, lo: np.ndarray, hi: np.ndarray, margin: float) -> np.ndarray:
    """The separating-axis test (module docstring) of triangles ``(p, 3, 3)`` against boxes
    ``(p, 3)`` grown by ``margin``: False only where an axis certainly separates them
    (comparisons with NaN or overflow say they meet). The box's own axes first, the other
    ten axes only on the pairs those leave."""
    centre = (lo + hi) / 2
    half = (hi - lo) / 2 + margin
    v = corners - centre[:, None, :]
    out = ~((v.min(axis=1) > half) | (v.max(axis=1) < -half)).any(axis=1)
    rows = np.flatnonzero(out)
    if rows.size == 0:
        return out
    h = [half[rows, a] for a in range(3)]
    x = [[v[rows, k, a] for a in range(3)] for k in range(3)]   # x[corner][axis]
    e = [[x[(k + 1) % 3][a] - x[k][a] for a in range(3)] for k in range(3)]
    # The triangle's normal.
    n = [e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
         e[0][0] * e[1][1] - e[0][1] * e[1][0]]
    p = [n[0] * x[k][0] + n[1] * x[k][1] + n[2] * x[k][2] for k in range(3)]
    apart = _clear(p, np.abs(n[0]) * h[0] + np.abs(n[1]) * h[1] + np.abs(n[2]) * h[2])
    # Each edge crossed with each box axis: the axis's own component is zero, so the
    # projection and the box's radius have two terms.
    for edge in e:
        for a in range(3):
            b, c = (a + 1) % 3, (a + 2) % 3
            p = [edge[c] * x[k][b] - edge[b] * x[k][c] for k in range(3)]
            apart |= _clear(p, np.abs(edge[c]) * h[b] + np.abs(edge[b]) * h[c])
    out[rows[apart]] = False
    return out


def _clear(p: list, r: np.ndarray) -> np.ndarray:
    """Whether the projections ``p`` (three corners) lie beyond ``[-r, r]``."""
    return (np.minimum(np.minimum(p[0], p[1]), p[2]) > r) | (np.maximum(np.maximum(p[0], p[1]), p[2]) < -r)
