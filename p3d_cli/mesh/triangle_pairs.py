"""What two triangles of a mesh do to each other, decided with exact orientation signs.

For a pair of non-degenerate faces ``A = (a0, a1, a2)`` and ``B = (b0, b1, b2)`` (vertices
shared when their coordinates are exactly equal), ``classify`` returns one of:

- ``NONE``: disjoint, or meeting only in the vertices or the edge they share;
- ``CROSSING``: not coplanar, and some point lies in the relative interior of both (the
  surfaces pass through each other there);
- ``OVERLAP``: coplanar, overlapping in a region of positive area, facing the same way (the
  region between is counted twice by the divergence theorem);
- ``FOLD``: coplanar, sharing an edge, overlapping in a region of positive area, facing opposite
  ways: the surface turns back onto itself across that edge;
- ``CONTACT``: not coplanar, touching along a segment of positive length that lies on an edge
  of one face (or on edges of both) and not in the other's interior only at isolated points.
  Whether the *surfaces* cross there depends on the faces around that edge, which
  ``p3d_cli.mesh.contacts`` decides; the pair alone is a touch.

Coplanar faces facing opposite ways without a shared edge (two parts pressed together, two
cubes sharing a face) touch and are ``NONE``; so are faces touching at a point.

Method (non-coplanar faces, all signs exact, ``p3d_cli.geometry.predicates``). With
``s`` the sides of B's vertices relative to A's plane and ``t`` those of A's relative to B's,
B meets A's plane in a segment ``I_B`` and A meets B's in ``I_A``, both on the line ``L`` where
the planes meet, and ``A ∩ B = I_A ∩ I_B``. Each segment is cut from its triangle by the two
edges leaving its *apex* (the vertex alone on its side of the other plane, or alone on it), so
its ends are ``apex-x ∩ plane``. For ends ``p`` on edge ``a-x`` of A and ``r`` on edge ``d-y``
of B, writing ``n_A, n_B`` for the normals and ``D = n_A × n_B`` for the direction of ``L``,

    orient3d(a, x, d, y) = D·(r - p) · (n_B·(a - x)) · (n_A·(d - y)) / |D|²,

(expand ``det(x - a, d - a, y - a)`` with ``a - p``, ``x - p`` along one direction in A's plane
and ``d - r``, ``y - r`` along one in B's), and the two last factors have known signs, so one
orientation sign compares two ends along ``L``. The ends of each segment come in a known order
(the apex's side and the face's winding fix it), so two signs decide whether ``I_A`` and
``I_B`` overlap, strictly or only at a point. This is the structure of Guigue and Devillers'
test ("Fast and robust triangle-triangle overlap test using orientation predicates", *J.
Graphics Tools* 8(1), 2003), derived again here because the classification needs more than
their yes/no: strict against touching overlap, and the segments' ends on edges or inside.
A face's open segment lies in its relative interior exactly when it has vertices strictly on
both sides of the other plane (it *straddles*); a crossing is a strict overlap of two
straddling faces. Coplanar faces are compared in the coordinate plane where A's normal is
largest, with the separating-axis test over the six edge lines (interiors overlap exactly when
no edge line has the other triangle in its closed outer half-plane).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.predicates import O3D_BOUND, Planes, exact_orient3d, orient2d

NONE, CROSSING, OVERLAP, FOLD, CONTACT = 0, 1, 2, 3, 4
#: Names of the kinds (``CONTACT`` pairs are resolved before anything is reported).
KINDS = {CROSSING: "crossing", OVERLAP: "overlap", FOLD: "fold"}

_NEXT = np.array([1, 2, 0])
_PREV = np.array([2, 0, 1])


def classify(points: np.ndarray, faces: np.ndarray, i: np.ndarray, j: np.ndarray, safe: bool = True):
    """Kinds of the face pairs ``(i[k], j[k])`` and, for ``CONTACT`` pairs, their touching edges.

    Parameters
    ----------
    points : (m, 3) float64
        Vertex coordinates (exact vertex ids: equal coordinates are one vertex).
    faces : (n, 3) int
        Vertex ids of each face; none of the faces given is degenerate (zero area).
    i, j : (k,) int
        Face pairs, ``i != j``.
    safe : bool
        ``predicates.in_safe_range(points)``.

    Returns
    -------
    kind : (k,) int8
    edges : (k, 2, 2) int64
        For ``CONTACT`` pairs: per face, the corners ``(c, c')`` of its edge on the contact
        line, or ``(-1, -1)`` when the contact lies in that face's interior. Unset elsewhere.
    """
    members = np.concatenate([i, j])
    corners = faces[members]
    k = np.arange(len(i))
    return classify_block(points[corners], corners, k, k + len(i), safe)


def classify_block(coords: np.ndarray, corners: np.ndarray, p: np.ndarray, q: np.ndarray, safe: bool = True):
    """``classify`` for the pairs ``(p[k], q[k])`` of a block of faces given by their corners'
    coordinates ``(e, 3, 3)`` and vertex ids ``(e, 3)`` (gathered once for all their pairs)."""
    k = len(p)
    kind = np.zeros(k, dtype=np.int8)
    edges = np.full((k, 2, 2), -1, dtype=np.int64)
    fa, fb = corners[p], corners[q]
    on_a, on_b = _shared_corners(fa, fb)
    A, B = coords[p], coords[q]
    shared = on_a[:, 0].view(np.int8) + on_a[:, 1].view(np.int8) + on_a[:, 2].view(np.int8)
    # Screen every pair at once: B's corners against A's plane; where B meets that plane only
    # in the vertices the faces share (most neighbours of a mesh), they meet only there.
    s = all_sides(A, B, on_b, safe)
    live = np.flatnonzero(_beyond_shared(s, shared))
    if live.size == 0:
        return kind, edges
    t = all_sides(B[live], A[live], on_a[live], safe)
    keep = _beyond_shared(t, shared[live])
    live, t = live[keep], t[keep]
    if live.size == 0:
        return kind, edges
    s, shared = s[live], shared[live]
    flat = (s == 0).all(axis=1)
    rows = np.flatnonzero(flat & (shared == 2))
    if rows.size:
        at = live[rows]
        kind[at] = _edge_pairs(A[at], B[at], on_a[at], on_b[at], safe)
    rows = np.flatnonzero(flat & (shared < 2))
    if rows.size:
        at = live[rows]
        kind[at] = _coplanar(A[at], B[at], safe)
    rows = np.flatnonzero(~flat)
    if rows.size:
        at = live[rows]
        kind[at], edges[at] = _crossing(A[at], B[at], fa[at], fb[at], s[rows], t[rows], safe)
    return kind, edges


def uncertified(corners: np.ndarray, p: np.ndarray, q: np.ndarray, certified: np.ndarray) -> np.ndarray:
    """The pairs ``(p[k], q[k])`` (rows of ``corners``, vertex ids) that share no vertex marked
    in ``certified`` (``p3d_cli.mesh.stars``): the others meet only as neighbours, no test needed."""
    a = [np.take(corners[:, c], p) for c in range(3)]
    b = [np.take(corners[:, c], q) for c in range(3)]
    sure = np.zeros(len(p), dtype=bool)
    for c in range(3):
        meets = (a[c] == b[0]) | (a[c] == b[1]) | (a[c] == b[2])
        sure |= meets & np.take(certified, a[c])
    return np.flatnonzero(~sure)


def all_sides(A: np.ndarray, B: np.ndarray, shared: np.ndarray, safe: bool) -> np.ndarray:
    """``orient3d`` of the three corners of each ``B`` ``(k, 3, 3)`` against the plane of ``A``:
    ``(k, 3)`` int8. Corners that are vertices of ``A`` (``shared``) are 0 without arithmetic
    (their difference from ``A``'s first corner is set to zero, which the filter proves)."""
    if not safe:            # products could overflow: every other corner in integers
        out = np.zeros(shared.shape, dtype=np.int8)
        rows, corners = np.nonzero(~shared)
        if rows.size:
            out[rows, corners] = exact_orient3d(A[rows, 0], A[rows, 1], A[rows, 2], B[rows, corners])
        return out
    a = A[:, 0]
    ux, uy, uz = A[:, 1, 0] - a[:, 0], A[:, 1, 1] - a[:, 1], A[:, 1, 2] - a[:, 2]
    vx, vy, vz = A[:, 2, 0] - a[:, 0], A[:, 2, 1] - a[:, 1], A[:, 2, 2] - a[:, 2]
    p0, p1, p2, p3, p4, p5 = uy * vz, uz * vy, uz * vx, ux * vz, ux * vy, uy * vx
    n = (p0 - p1, p2 - p3, p4 - p5)
    pn = (np.abs(p0) + np.abs(p1), np.abs(p2) + np.abs(p3), np.abs(p4) + np.abs(p5))
    w = B - a[:, None, :]
    w[shared] = 0.0
    det = w[:, :, 0] * n[0][:, None]
    det += w[:, :, 1] * n[1][:, None]
    det += w[:, :, 2] * n[2][:, None]
    np.abs(w, out=w)
    perm = w[:, :, 0] * pn[0][:, None]
    perm += w[:, :, 1] * pn[1][:, None]
    perm += w[:, :, 2] * pn[2][:, None]
    out = (det > 0).view(np.int8) - (det < 0).view(np.int8)
    perm *= O3D_BOUND
    unsure = np.abs(det) <= perm
    unsure &= perm != 0
    rows, corners = np.nonzero(unsure)
    if rows.size:
        out[rows, corners] = exact_orient3d(A[rows, 0], A[rows, 1], A[rows, 2], B[rows, corners])
    return out


def _beyond_shared(signs: np.ndarray, shared: np.ndarray) -> np.ndarray:
    """Where a face may meet the other beyond their shared vertices: its corners do not lie
    strictly on one side of the other's plane apart from the shared ones."""
    a, b, c = signs[:, 0], signs[:, 1], signs[:, 2]
    # Apart from the zeros (shared corners, or corners on the plane), one sign at most:
    # the sum's size equals the count of nonzero signs exactly then.
    nonzero = (a != 0).view(np.int8) + (b != 0).view(np.int8) + (c != 0).view(np.int8)
    one_sided = np.abs(a + b + c) == nonzero
    return ~one_sided | (nonzero != 3 - shared)


def _shared_corners(fa: np.ndarray, fb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(k, 3)`` masks of the corners of A, and of B, that are a vertex of the other face."""
    on_a = np.empty(fa.shape, dtype=bool)
    on_b = np.zeros(fb.shape, dtype=bool)
    a = [np.ascontiguousarray(fa[:, p]) for p in range(3)]
    b = [np.ascontiguousarray(fb[:, q]) for q in range(3)]
    for p in range(3):
        e0, e1, e2 = a[p] == b[0], a[p] == b[1], a[p] == b[2]
        on_a[:, p] = e0 | e1 | e2
        on_b[:, 0] |= e0
        on_b[:, 1] |= e1
        on_b[:, 2] |= e2
    return on_a, on_b


def _first(mask: np.ndarray) -> np.ndarray:
    """The first column set in each row of a ``(k, 3)`` mask (2 if none of the first two)."""
    return np.where(mask[:, 0], 0, np.where(mask[:, 1], 1, 2))


def _edge_pairs(A, B, on_a, on_b, safe) -> np.ndarray:
    """Coplanar faces sharing exactly one edge: a fold or an overlap when on the same side of it."""
    free_a, free_b = _first(~on_a), _first(~on_b)           # the corners off the shared edge
    rows = np.arange(len(A))
    planes = Planes(A[:, 0], A[:, 1], A[:, 2], safe)
    kind = np.zeros(len(A), dtype=np.int8)
    flat = rows
    if flat.size:
        u = A[flat, _NEXT[free_a[flat]]]                    # the shared edge, as A's corners
        v = A[flat, _PREV[free_a[flat]]]
        axes = _projection(planes, flat, A[flat], safe)
        ua, va = _project(u, axes), _project(v, axes)
        near_a = orient2d(ua, va, _project(A[flat, free_a[flat]], axes), safe)
        near_b = orient2d(ua, va, _project(B[flat, free_b[flat]], axes), safe)
        facing = _facing(A[flat], axes, safe) == _facing(B[flat], axes, safe)
        together = near_a == near_b                         # both nonzero: faces not degenerate
        kind[flat[together & facing]] = OVERLAP
        kind[flat[together & ~facing]] = FOLD
    return kind


def _projection(planes: Planes, rows: np.ndarray, A: np.ndarray, safe: bool) -> np.ndarray:
    """For each row, a coordinate axis to drop so that face A projects to a proper triangle:
    the largest component of its (rounded) normal, and another axis where that is exactly flat."""
    normal = np.abs(np.stack([n[rows] for n in planes.normal], axis=1))
    axes = np.argmax(normal, axis=1)
    for _ in range(2):
        a, b, c = (_project(A[:, k], axes) for k in range(3))
        flat = np.flatnonzero(orient2d(a, b, c, safe) == 0)
        if flat.size == 0:
            break
        axes[flat] = (axes[flat] + 1) % 3
    return axes


def _project(x: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """``(k, 3)`` points without coordinate ``axes[k]``: ``(k, 2)``, keeping the cyclic order
    of the two others (so that orientations are those seen along ``+axis``)."""
    rows = np.arange(len(x))
    return np.stack([x[rows, (axes + 1) % 3], x[rows, (axes + 2) % 3]], axis=1)


def _facing(T, axes, safe) -> np.ndarray:
    """The orientation of each face ``(k, 3, 3)`` seen along its projection axis (+1 or -1)."""
    a, b, c = (_project(T[:, k], axes) for k in range(3))
    return orient2d(a, b, c, safe)


def _apex(sign: np.ndarray):
    """Per row of corner signs (not all equal and nonzero, not all zero): the apex corner, the
    sign of (apex side - other side), and whether the face straddles the plane."""
    nxt, prv = sign[:, _NEXT], sign[:, _PREV]
    alone = (sign != 0) & (nxt != sign) & (prv != sign)
    on_it = (sign == 0) & (nxt == prv) & (nxt != 0)
    apex = np.argmax(alone | on_it, axis=1)
    rows = np.arange(len(sign))
    s_apex = sign[rows, apex].astype(np.int64)
    factor = np.where(s_apex != 0, s_apex, -sign[rows, _NEXT[apex]].astype(np.int64))
    straddle = (sign > 0).any(axis=1) & (sign < 0).any(axis=1)
    return apex, factor, straddle


def _crossing(A, B, fa, fb, s, t, safe):
    """Non-coplanar pairs whose faces each meet the other's plane: compare ``I_A`` and ``I_B``."""
    k = len(A)
    rows = np.arange(k)
    apex_a, f_a, straddle_a = _apex(t)
    apex_b, f_b, straddle_b = _apex(s)
    a, d = A[rows, apex_a], B[rows, apex_b]
    # Ends of I_A lie on edges apex-x; in the order along L (module docstring): for f_a > 0
    # the end on the edge to the previous corner comes first.
    a_lo = np.where(f_a > 0, _PREV[apex_a], _NEXT[apex_a])
    a_hi = np.where(f_a > 0, _NEXT[apex_a], _PREV[apex_a])
    b_lo = np.where(f_b > 0, _NEXT[apex_b], _PREV[apex_b])
    b_hi = np.where(f_b > 0, _PREV[apex_b], _NEXT[apex_b])
    factor = (f_a * f_b).astype(np.int8)
    # cmp(p, r) = sign(D·(r - p)) = orient3d(a, x, d, y) · f_a · f_b
    a_id, d_id = fa[rows, apex_a], fb[rows, apex_b]
    lo_hi = _orient(a, A[rows, a_lo], d, B[rows, b_hi], a_id, fa[rows, a_lo], d_id, fb[rows, b_hi], safe)
    hi_lo = _orient(a, A[rows, a_hi], d, B[rows, b_lo], a_id, fa[rows, a_hi], d_id, fb[rows, b_lo], safe)
    lo_hi *= factor                                        # lo_A against hi_B
    hi_lo *= factor                                        # hi_A against lo_B
    strict = (lo_hi > 0) & (hi_lo < 0)
    kind = np.zeros(k, dtype=np.int8)
    kind[strict & straddle_a & straddle_b] = CROSSING
    edges = np.full((k, 2, 2), -1, dtype=np.int64)
    # A segment of contact: a strict overlap of two segments of positive length (a face that
    # only touches the other's plane at a vertex has a one-point segment), one of which is an
    # edge lying in the other's plane -- the surfaces may cross through that edge.
    a_edge_on, b_edge_on = (t == 0).sum(axis=1) == 2, (s == 0).sum(axis=1) == 2
    contact = (strict & ~(straddle_a & straddle_b) & (a_edge_on | b_edge_on)
               & (straddle_a | a_edge_on) & (straddle_b | b_edge_on))
    kind[contact] = CONTACT
    for face, signs, on in ((0, t, a_edge_on), (1, s, b_edge_on)):
        rows_on = np.flatnonzero(contact & on)
        zero = signs[rows_on] == 0
        first = np.argmax(zero, axis=1)
        second = 2 - np.argmax(zero[:, ::-1], axis=1)
        edges[rows_on, face, 0], edges[rows_on, face, 1] = first, second
    return kind, edges


def _orient(a, x, d, y, a_id, x_id, d_id, y_id, safe) -> np.ndarray:
    """``orient3d(a, x, d, y)`` row by row. Two of the four being one vertex (a corner the
    faces share) makes it exactly zero: such rows get points the filter proves zero at once (a
    repeated point, so a zero difference) instead of a float value it cannot decide."""
    d = np.where((x_id == d_id)[:, None], a, d)
    y = np.where(((y_id == a_id) | (y_id == x_id) | (y_id == d_id))[:, None], a, y)
    return Planes(a, x, d, safe).side(y)


def _coplanar(A, B, safe) -> np.ndarray:
    """Coplanar pairs sharing at most one vertex: ``OVERLAP`` when their interiors overlap and
    they face the same way (facing opposite ways, they are pressed together: ``NONE``)."""
    rows = np.arange(len(A))
    axes = _projection(Planes(A[:, 0], A[:, 1], A[:, 2], safe), rows, A, safe)
    a = [_project(A[:, c], axes) for c in range(3)]
    b = [_project(B[:, c], axes) for c in range(3)]
    o_a = orient2d(a[0], a[1], a[2], safe)
    o_b = orient2d(b[0], b[1], b[2], safe)
    separated = np.zeros(len(A), dtype=bool)
    for edge_of, against, o in ((a, b, o_a), (b, a, o_b)):
        for c in range(3):
            p, q = edge_of[c], edge_of[(c + 1) % 3]
            outer = np.ones(len(A), dtype=bool)
            for x in against:
                outer &= orient2d(p, q, x, safe) * o <= 0
            separated |= outer
    kind = np.zeros(len(A), dtype=np.int8)
    kind[~separated & (o_a == o_b)] = OVERLAP
    return kind
