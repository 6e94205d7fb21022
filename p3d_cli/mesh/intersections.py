"""Self-intersections of a triangle surface: the face pairs whose interiors cross or overlap.

The test runs in three steps, all exact (docs/method.md, "Self-intersections"):

1. **Broad phase** (``p3d_cli.mesh.broadphase``): the pairs of faces whose bounding boxes
   overlap, by a hierarchical grid; never all pairs.
2. **Pairs** (``p3d_cli.mesh.triangle_pairs``): each such pair is classified with exact
   orientation signs (``p3d_cli.geometry.predicates``). Faces that only share a vertex or an
   edge, or touch, are never reported; crossings, coplanar overlaps facing the same way and
   folds (coplanar faces sharing an edge and lying on each other) are, whatever the scale or
   the offset of the coordinates.
3. **Lines of contact** (``p3d_cli.mesh.contacts``): where faces only touch along a segment --
   an edge lying in another face's plane, collinear edges, an edge used by more than two faces
   -- the faces around that line decide, in rational arithmetic, whether the sheets cross.

Degenerate (zero-area) faces take no part: they bound nothing, and ``p3d check`` reports them
by its ``no-degenerate`` check.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.predicates import in_safe_range, orient2d
from p3d_cli.mesh.broadphase import box_frame, outward_boxes, pair_blocks
from p3d_cli.mesh.compiled_grid import compiled_pairs
from p3d_cli.mesh.kernels import compiled
from p3d_cli.mesh.contacts import IntegerPoints, Line, crossing_faces, face_half_planes
from p3d_cli.mesh.solidity_report import SAMPLES, Crossing, SelfIntersections
from p3d_cli.mesh.stars import certified_vertices, paired_vertices
from p3d_cli.mesh.meeting import meeting_point
from p3d_cli.mesh.triangle_pairs import CONTACT, CROSSING, FOLD, KINDS, NONE, classify, uncertified

#: Faces per block when computing boxes, pairs per call of the pair test (bounded temporaries).
_BLOCK = 1 << 16
_PAIRS = 1 << 15


def self_intersections(points: np.ndarray, faces: np.ndarray, degenerate: np.ndarray | None = None,
                       nonmanifold_edges: np.ndarray | None = None, fans: bool = False,
                       patches: np.ndarray | None = None, nearby: np.ndarray | None = None) -> SelfIntersections:
    """The face pairs of an indexed triangle surface whose interiors cross or overlap.

    Parameters
    ----------
    points : (m, 3) float64
        Vertex coordinates, one row per distinct point (vertices are matched by exact
        coordinates before: equal points must have one id).
    faces : (n, 3) int
        Vertex ids of each face.
    degenerate : (z,) int, optional
        The faces of zero area (computed exactly when not given).
    nonmanifold_edges : (e, 2) int, optional
        Vertex ids of the edges used by more than two faces (found from the faces when not
        given).
    fans : bool
        The mesh is closed, without non-manifold edges or vertices: every vertex's faces form
        one fan. The fans whose faces provably meet only as neighbours do
        (``p3d_cli.mesh.stars``) spare their pairs the pair test; without ``fans``, only the
        vertices whose every edge pairs up one each way are tried (``paired_vertices``).
    patches : (n,) int, optional
        A label per face (negative: none). Faces of one label are known to meet each other
        only in the edges and corners they share (a triangulation of a polygon seen on a
        plane, such as a filled hole): the pair test would find their pairs ``NONE``, so they
        are not given to it. Lines of contact still take every face around them.
    nearby : (p, 2) int, optional
        With ``patches``: every pair of faces, one of them in a patch, that may touch (a
        superset, such as ``p3d_cli.repairs.near``'s). These pairs are tested, and the broad
        phase pairs only the faces in no patch: a pair with a face in a patch and not among them
        is disjoint, which the pair test would find ``NONE`` without a contact (the boxes of a
        fan of slivers hold many faces its triangles miss, and each other's).

    Returns
    -------
    SelfIntersections
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    faces = np.asarray(faces)
    n = len(faces)
    if patches is not None:
        patches = np.asarray(patches, dtype=np.int64)
    # In pieces: the whole array's magnitudes at once would cost twice the points' memory.
    safe = all(in_safe_range(points[at:at + _BLOCK]) for at in range(0, len(points), _BLOCK))
    if degenerate is None:
        degenerate = zero_area_faces(points, faces, safe)
    index = np.int32 if n < 2**31 else np.int64
    if len(degenerate):
        live = np.ones(n, dtype=bool)
        live[np.asarray(degenerate, dtype=np.int64)] = False
        live = np.flatnonzero(live).astype(index)
    else:
        live = np.arange(n, dtype=index)
    if nonmanifold_edges is None:
        nonmanifold_edges = crowded_edges(faces[live])
    crowded = {(min(u, v), max(u, v)) for u, v in np.asarray(nonmanifold_edges).tolist()}
    found: list[np.ndarray] = []
    kinds: list[np.ndarray] = []
    contacts: list[tuple] = []
    certified = None
    if live.size > 1:
        certified = certified_vertices(points, faces, safe)
        if not fans:                 # only where every edge pairs up (the fans are closed there)
            certified &= paired_vertices(faces, len(points))
    boxed = live
    if patches is not None and nearby is not None:
        # The patches' faces are paired with the faces given as near them, the others by the
        # broad phase among themselves.
        boxed = live[patches[live] < 0]
        given = _given_pairs(patches, nearby, live, n)
        for at in range(0, given[0].size, _PAIRS):
            _test(points, faces, [(given[0][at:at + _PAIRS], given[1][at:at + _PAIRS])], safe, crowded, found,
                  kinds, contacts, patches)
    fast = compiled()
    chunks = (compiled_pairs(fast, points, faces, boxed, certified) if fast is not None and safe and boxed.size > 1
              else None)
    if chunks is not None:
        # The compiled grid: the pairs to test, the certified fans' set aside, in batches.
        batch: list[tuple[np.ndarray, np.ndarray]] = []
        waiting = 0
        for i, j in chunks:
            for at in range(0, i.size, _PAIRS):
                batch.append((i[at:at + _PAIRS], j[at:at + _PAIRS]))
                waiting += batch[-1][0].size
                if waiting >= _PAIRS:
                    _test(points, faces, batch, safe, crowded, found, kinds, contacts, patches)
                    batch, waiting = [], 0
        _test(points, faces, batch, safe, crowded, found, kinds, contacts, patches)
    elif boxed.size > 1:
        lo, hi = _boxes(points, faces, boxed)
        pending: list[tuple[np.ndarray, np.ndarray]] = []
        waiting = 0
        assert certified is not None  # noqa: S101 - made above whenever two faces are live
        for members, p, q in pair_blocks(lo, hi):
            members = boxed[members]
            corners = faces[members]
            # The pairs left once the certified fans' are set aside: tested in batches.
            rest = uncertified(corners, p, q, certified)
            pending.append((members[p[rest]], members[q[rest]]))
            waiting += rest.size
            if waiting >= _PAIRS:
                _test(points, faces, pending, safe, crowded, found, kinds, contacts, patches)
                pending, waiting = [], 0
        _test(points, faces, pending, safe, crowded, found, kinds, contacts, patches)
    lines = _line_crossings(points, faces, live, contacts, nonmanifold_edges)
    return _result(points, faces, found, kinds, lines, live.size)


def zero_area_faces(points: np.ndarray, faces: np.ndarray, safe: bool = True) -> np.ndarray:
    """Faces whose three corners are collinear or repeated, exactly: all three projections
    onto the coordinate planes have zero signed area."""
    flat = np.ones(len(faces), dtype=bool)
    for axis in range(3):
        rows = np.flatnonzero(flat)
        if rows.size == 0:
            break
        keep = [(axis + 1) % 3, (axis + 2) % 3]
        a, b, c = (points[faces[rows, k]][:, keep] for k in range(3))
        flat[rows] = orient2d(a, b, c, safe) == 0
    return np.flatnonzero(flat)


def crowded_edges(faces: np.ndarray) -> np.ndarray:
    """Vertex ids ``(e, 2)`` of the edges used by more than two of ``faces``."""
    if len(faces) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    a = faces.astype(np.int64)
    lo = np.minimum(a, np.roll(a, -1, axis=1)).ravel()
    hi = np.maximum(a, np.roll(a, -1, axis=1)).ravel()
    m = int(a.max()) + 1
    if int(a.min()) >= 0 and m <= 1 << 31:
        # One integer per edge, ordered as the (lo, hi) rows: a sort of numbers instead of
        # numpy's unique of rows (ten times slower), with the same edges in the same order.
        key, counts = np.unique(lo * m + hi, return_counts=True)
        key = key[counts > 2]
        return np.stack([key // m, key % m], axis=1)
    keys = np.unique(np.stack([lo, hi], axis=1), axis=0, return_counts=True)
    return keys[0][keys[1] > 2]


def _test(points, faces, pending, safe, crowded, found, kinds, contacts, patches=None) -> None:
    """Classify the pending pairs (but those within one of ``patches``) and keep what they
    find (``found``/``kinds``/``contacts``)."""
    if not pending:
        return
    i = np.concatenate([x for x, _ in pending])
    j = np.concatenate([y for _, y in pending])
    if patches is not None and i.size:
        apart = (patches[i] < 0) | (patches[i] != patches[j])
        i, j = i[apart], j[apart]
    if i.size == 0:
        return
    kind, edges = classify(points, faces, i, j, safe)
    _keep(kind, edges, i, j, faces, crowded, found, kinds, contacts)


def _given_pairs(patches: np.ndarray, nearby: np.ndarray, live: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of ``nearby`` with a face in a patch, both faces live and not in one patch,
    each once (smaller face first, ascending)."""
    pairs = np.asarray(nearby, dtype=np.int64).reshape(-1, 2)
    alive = np.zeros(n, dtype=bool)
    alive[live] = True
    i, j = pairs.min(axis=1), pairs.max(axis=1)
    keep = (alive[i] & alive[j] & (i != j) & ((patches[i] >= 0) | (patches[j] >= 0))
            & ((patches[i] < 0) | (patches[i] != patches[j])))
    keys = np.unique(i[keep] * n + j[keep])
    index = live.dtype
    return (keys // n).astype(index), (keys % n).astype(index)


def _keep(kind, edges, i, j, faces, crowded, found, kinds, contacts) -> None:
    """Keep the reported pairs of one test (and the contacts, for the lines' test)."""
    if crowded:
        _unfold(kind, faces, i, j, crowded)
    hit = np.flatnonzero((kind != 0) & (kind != CONTACT))
    if hit.size:
        found.append(np.stack([i[hit], j[hit]], axis=1))
        kinds.append(kind[hit])
    touch = np.flatnonzero(kind == CONTACT)
    if touch.size:
        contacts.append((i[touch], j[touch], edges[touch]))


def _unfold(kind: np.ndarray, faces: np.ndarray, i: np.ndarray, j: np.ndarray, crowded: set) -> None:
    """A fold is a surface turning back across an edge of its own: faces lying on each other
    across an edge that more faces use are two sheets pressed together (two cubes sharing a
    face, triangulated differently), which the windings around that edge judge instead."""
    for k in np.flatnonzero(kind == FOLD):
        shared = sorted(set(faces[i[k]].tolist()) & set(faces[j[k]].tolist()))
        if tuple(shared) in crowded:
            kind[k] = NONE


def _boxes(points, faces, live):
    """Boxes of the live faces in float32, about the points' centre and scaled by a power of two
    to a span near 1 (far from the world origin float32 coordinates would be too coarse, every
    box 8 wide at 1e8; huge or tiny parts would over- or underflow), rounded outwards with a
    float32 step of margin beyond the float64 rounding of the shift, block by block. Boxes only
    choose which pairs are tested: any consistent map that keeps them overlapping does."""
    centre, shift = box_frame(points)
    lo = np.empty((live.size, 3), dtype=np.float32)
    hi = np.empty((live.size, 3), dtype=np.float32)
    for start in range(0, live.size, _BLOCK):
        f = faces[live[start:start + _BLOCK]]
        a, b, c = (np.take(points, f[:, k], axis=0) for k in range(3))
        low, high = np.minimum(a, b), np.maximum(a, b)
        low = np.ldexp(np.minimum(low, c, out=low) - centre, shift)
        high = np.ldexp(np.maximum(high, c, out=high) - centre, shift)
        low32, high32 = outward_boxes(low, high)
        lo[start:start + _BLOCK] = np.nextafter(low32, np.float32(-np.inf))
        hi[start:start + _BLOCK] = np.nextafter(high32, np.float32(np.inf))
    return lo, hi


class _Stars:
    """The live faces around each vertex, built only when a line of contact needs them."""

    def __init__(self, faces: np.ndarray, live: np.ndarray):
        corners = faces[live].ravel()
        self.order = np.argsort(corners, kind="stable")
        self.sorted = corners[self.order]
        self.live = live

    def around(self, vertex: int) -> set[int]:
        lo, hi = np.searchsorted(self.sorted, [vertex, vertex + 1])
        return {int(f) for f in self.live[self.order[lo:hi] // 3]}

    def edge(self, u: int, v: int) -> list[int]:
        return sorted(self.around(u) & self.around(v))


def _line_crossings(points, faces, live, contacts, nonmanifold_edges) -> dict:
    """Pairs (``{(f, g): "crossing"}``) where sheets cross along lines their faces only touch."""
    out: dict = {}
    if not contacts and not len(nonmanifold_edges):
        return out
    stars = _Stars(faces, live)
    grid = IntegerPoints(points)
    seen: set[tuple] = set()
    for i, j, edges in contacts:
        for f, g, e in zip(i.tolist(), j.tolist(), edges.tolist()):
            own = [(f, e[0]), (g, e[1])]
            if e[0][0] < 0 or e[1][0] < 0:      # a face's interior and the other's edge
                (inner, _), (other, corners) = own if e[0][0] < 0 else own[::-1]
                u, v = (int(faces[other][c]) for c in corners)
                key: tuple = ("face", inner, min(u, v), max(u, v))
                sheets = [[inner], stars.edge(u, v)]
            else:                               # two collinear edges
                (ua, va), (u, v) = ((int(faces[h][c]) for c in cs) for h, cs in own)
                key = ("edges", min(ua, va), max(ua, va), min(u, v), max(u, v))
                sheets = [stars.edge(ua, va), stars.edge(u, v)]
            if key in seen:
                continue
            seen.add(key)
            line = Line(grid[u], grid[v])
            half_planes = [h for face in dict.fromkeys(sum(sheets, []))
                           for h in face_half_planes(grid, faces, face, line)]
            for pair in crossing_faces(line, half_planes):
                out.setdefault(pair, "crossing")
    for u, v in np.asarray(nonmanifold_edges).tolist():
        line = Line(grid[u], grid[v])
        half_planes = [h for face in stars.edge(u, v) for h in face_half_planes(grid, faces, face, line)]
        for pair in crossing_faces(line, half_planes):
            out.setdefault(pair, "crossing")
    return out


def _result(points, faces, found, kinds, lines: dict, tested: int) -> SelfIntersections:
    """Every pair once (sorted, the smaller face first), counts by kind, and samples."""
    pairs = np.concatenate(found) if found else np.zeros((0, 2), dtype=np.int64)
    kind = np.concatenate(kinds) if kinds else np.zeros(0, dtype=np.int8)
    pairs = np.sort(pairs.astype(np.int64), axis=1)
    names = {(int(a), int(b)): KINDS[int(k)] for (a, b), k in zip(pairs.tolist(), kind.tolist())}
    for pair, name in lines.items():
        names.setdefault(pair, name)
    ordered = sorted(names)
    pairs = np.array(ordered, dtype=np.int64).reshape(-1, 2)
    labels = tuple(names[p] for p in ordered)
    by_kind = {name: labels.count(name) for name in ("crossing", "overlap", "fold")}
    samples = tuple(Crossing(p, names[p], meeting_point(points[faces[p[0]]], points[faces[p[1]]]))
                    for p in ordered[:SAMPLES])
    return SelfIntersections(len(ordered), by_kind, samples, pairs, labels, tested)


__all__ = ["CROSSING", "SelfIntersections", "crowded_edges", "self_intersections", "zero_area_faces"]
