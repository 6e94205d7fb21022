"""Filling one hole: a triangulation of its loop that uses only the loop's own corners.

A loop is filled when it is flat enough and simple seen along its normal:

1. **Its plane.** The loop's normal is Newell's (the sum of ``p_i × p_(i+1)``, twice its
   vector area; M. E. Newell's method, in F. S. Hill, *Computer Graphics*, 1990): exact for a
   planar polygon, the best-fitting direction for a nearly planar one. Its *flatness* is the
   largest distance of a corner from the plane through the corners' centroid, over the loop's
   size (the largest extent of its box). A loop with no area (collinear corners: a slit or a
   T-junction) is left.
2. **A simple projection.** The corners are projected on the coordinate plane most nearly
   parallel to the loop (dropping the normal's largest axis): the projection keeps the
   coordinates exact, so every test after it is an exact orientation sign
   (``p3d_cli.geometry.predicates.orient2d``). The projected polygon must be simple (no two edges
   meet except neighbours at their shared corner); then its triangles, lifted back, are a graph
   over that plane and cannot cross each other.
   A loop too bent for any coordinate plane (``fill_holes="any"`` only) is seen in its own
   plane instead, with rounded coordinates: the triangulation is then only a choice, and its
   faces are tested exactly after (non-zero area here, no crossing in ``p3d_cli.repairs.holes``).
3. **Ear clipping** on the projected polygon (an ear: a strictly convex corner whose triangle,
   closed, holds no other corner; G. H. Meisters, "Polygons have ears", *Amer. Math.
   Monthly* 82, 1975): every triangle has non-zero area, so none is degenerate, and an ear whose
   new edge the mesh already has (it would make that edge non-manifold) is passed over.

Each triangle is wound like the loop, which runs against the faces around the hole, so the
filled patch is oriented with them.
"""

from __future__ import annotations

from bisect import bisect_left, bisect_right
from dataclasses import dataclass
from typing import Callable

import numpy as np

from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.faces import zero_area_faces
from p3d_cli.mesh.kernels import compiled
from p3d_cli.geometry.predicates import CCW_BOUND, in_safe_range, orient2d, orient2d_about


@dataclass(frozen=True)
class Hole:
    """One loop of boundary edges and what became of it.

    Attributes
    ----------
    vertices : (k,) int64
        Vertex ids of the loop's corners, in its winding.
    edges : int
        Number of boundary edges (``k``).
    centre : (float, float, float)
        The centroid of its corners (where to find it).
    size : float
        The largest extent of its box.
    flatness : float
        Largest distance of a corner from the corners' mean plane, over ``size`` (0: planar; nan
        for a loop with no area).
    triangles : (t, 3) int64 or None
        The filling triangles (vertex ids), or None when the hole is left.
    reason : str or None
        Why it was left.
    replaced : (int, (3,) int64) or None
        A hole of no area closed by splitting the face across it
        (``p3d_cli.repairs.junctions``): that face, and the triangle that takes its place
        (``triangles`` are then the split's other triangles).
    projected : bool
        ``triangles`` are an ear clipping of the loop seen exactly on a coordinate plane (step
        2 of the module docstring): they meet each other only in the edges and corners they
        share (``p3d_cli.repairs.solidity`` does not test their pairs).
    """

    vertices: np.ndarray
    edges: int
    centre: tuple[float, float, float]
    size: float
    flatness: float
    triangles: np.ndarray | None = None
    reason: str | None = None
    replaced: tuple[int, np.ndarray] | None = None
    projected: bool = False

    @property
    def filled(self) -> bool:
        return self.triangles is not None


#: Why a loop of collinear corners is left (``p3d_cli.repairs.holes`` tries a face split then).
NO_AREA = "it encloses no area (its edges are collinear: a slit or a T-junction)"
#: Why a loop is left whose every triangulation repeats a mesh edge or has a face of no area.
NO_TRIANGULATION = ("every triangulation of it would repeat an edge the mesh already has "
                    "(making it non-manifold) or make a face of zero area")
#: Fill policies: ``flat`` fills loops within the flatness limit, ``any`` every simple loop.
POLICIES = ("flat", "any")
#: Default flatness limit: a corner at most this fraction of the loop's size off its plane
#: (float32 rounding of a planar loop is ~1e-7 of its size; a scan's holes are 1e-2 and more).
FLATNESS = 1e-3
#: Default largest hole filled, in edges (larger openings are usually meant: the mouth of a
#: vessel; their triangulation also costs the square of the edges).
MAX_EDGES = 1000
#: Edge pairs tested together by the simplicity test (bounded temporaries).
PAIRS = 1 << 18
#: Ear clipping tries the corners in an ear's x range one at a time, on Python floats, up to
#: this many (an ear of a round loop has a few: numpy's calls would cost more than the tests);
#: more go through the array test.
LOOPED = 24


def fill_hole(points: np.ndarray, vertices: np.ndarray, *, policy: str = "flat", flatness: float = FLATNESS,
              max_edges: int = MAX_EDGES, has_edge: Callable[[int, int], bool] = lambda u, v: False) -> Hole:
    """Triangulate one loop (see the module docstring), or say why not.

    Parameters
    ----------
    points : (m, 3) float
        Coordinates by vertex id.
    vertices : (k,) int
        The loop's vertex ids in its winding (against the faces around it).
    policy : {"flat", "any"}
        ``any`` also fills loops beyond the flatness and size limits.
    flatness : float
        The flatness limit of ``flat``.
    max_edges : int
        The largest loop ``flat`` fills.
    has_edge : callable
        ``has_edge(u, v)``: whether the mesh (or a hole filled before) already has the edge;
        such an edge is never added again.
    """
    vertices = np.asarray(vertices, dtype=np.int64)
    k = vertices.size
    # Gathered, then widened: converting the whole array first cost a pass over every vertex
    # per hole (the 10,000 one-face holes of a scan: 8 s); the values are the same.
    corners = np.asarray(np.asarray(points)[vertices], dtype=np.float64)
    centre = corners.mean(axis=0)
    size = float((corners.max(axis=0) - corners.min(axis=0)).max())
    relative = corners - centre
    normal = np.cross(relative, np.roll(relative, -1, axis=0)).sum(axis=0)
    length = float(np.sqrt(normal @ normal))
    where = (float(centre[0]), float(centre[1]), float(centre[2]))

    def left(reason: str, flat: float = float("nan")) -> Hole:
        return Hole(vertices, k, where, size, flat, None, reason)

    if k < 3 or length == 0 or size == 0:
        return left(NO_AREA)
    deviation = float(np.abs(relative @ (normal / length)).max())
    flat = deviation / size
    if policy == "flat" and flat > flatness:
        return left(_not_flat(deviation, flat, flatness), flat)
    if policy == "flat" and k > max_edges:
        return left(_too_large(k, max_edges), flat)
    projected = False
    if k == 3:
        # A loop of three corners is its own triangulation (what ear clipping gives it, in its
        # winding), simple whenever it has an area: only the exact area test is left. The many
        # one-face holes of a scan or a damaged file are filled without the polygon's machinery.
        triangles = vertices[[2, 0, 1]].reshape(1, 3)
    else:
        found = _triangulated(corners, relative, normal, length, vertices, policy, has_edge)
        if isinstance(found, str):
            return left(found, flat)
        triangles, projected = found
    if triangles is not None and zero_area_faces(
            columns(np.asarray(np.asarray(points)[triangles], dtype=np.float64))).size:
        triangles = None
    if triangles is None:
        return left(NO_TRIANGULATION, flat)
    return Hole(vertices, k, where, size, flat, triangles, None, projected=projected)


def _not_flat(deviation: float, flat: float, flatness: float) -> str:
    return (f"not flat: a corner lies {deviation:.3g} ({flat:.2g} of its size) off the loop's plane, "
            f"over the limit {flatness:g}")


def _too_large(k: int, max_edges: int) -> str:
    return f"larger than the limit: {k} edges, over {max_edges}"


def fill_triangles(points: np.ndarray, loops: np.ndarray, *, policy: str = "flat", flatness: float = FLATNESS,
                   max_edges: int = MAX_EDGES) -> list[Hole]:
    """``fill_hole`` of many loops of three corners at once: the same ``Hole`` for each, bit
    for bit (the one-face holes of a scan or a damaged file come by the thousand, and numpy's
    cost per call was most of their filling).

    Every elementwise step is ``fill_hole``'s on a stack of loops: the centroid, the box, the
    Newell normal (``np.cross`` and a sum of three rows, in their order) and the exact zero-area
    test of the triangles. The two products that numpy may hand to BLAS (the normal's length
    and the corners' distances from the plane) are made per loop with the very calls of
    ``fill_hole``, so their roundings are the same.

    Parameters
    ----------
    points : (m, 3) float
        Coordinates by vertex id.
    loops : (h, 3) int
        Each loop's vertex ids in its winding.
    """
    loops = np.asarray(loops, dtype=np.int64).reshape(-1, 3)
    if len(loops) == 0:
        return []
    corners = np.asarray(np.asarray(points)[loops], dtype=np.float64)          # (h, 3 corners, 3 axes)
    centre = corners.mean(axis=1)
    size = (corners.max(axis=1) - corners.min(axis=1)).max(axis=1)
    relative = corners - centre[:, None, :]
    normal = np.cross(relative, np.roll(relative, -1, axis=1)).sum(axis=1)
    triangles = loops[:, [2, 0, 1]]
    zero = np.zeros(len(loops), dtype=bool)
    zero[zero_area_faces(columns(np.asarray(np.asarray(points)[triangles], dtype=np.float64)))] = True
    holes = []
    for i, (vertices, where, extent) in enumerate(zip(loops, centre.tolist(), size.tolist())):
        n = normal[i]
        length = float(np.sqrt(n @ n))
        place = (where[0], where[1], where[2])
        if length == 0 or extent == 0:
            holes.append(Hole(vertices, 3, place, extent, float("nan"), None, NO_AREA))
            continue
        deviation = float(np.abs(relative[i] @ (n / length)).max())
        flat = deviation / extent
        if policy == "flat" and flat > flatness:
            reason = _not_flat(deviation, flat, flatness)
        elif policy == "flat" and 3 > max_edges:
            reason = _too_large(3, max_edges)
        elif zero[i]:
            reason = NO_TRIANGULATION
        else:
            holes.append(Hole(vertices, 3, place, extent, flat, triangles[i:i + 1], None))
            continue
        holes.append(Hole(vertices, 3, place, extent, flat, None, reason))
    return holes


def _triangulated(corners: np.ndarray, relative: np.ndarray, normal: np.ndarray, length: float,
                  vertices: np.ndarray, policy: str, has_edge) -> tuple[np.ndarray | None, bool] | str:
    """Ear clipping of a loop of four corners or more, seen along its normal: its triangles
    (None when clipping gets stuck) and whether they were clipped on a coordinate plane, or
    why the loop cannot be filled (it crosses itself)."""
    axis = int(np.argmax(np.abs(normal)))
    plane = np.ascontiguousarray(corners[:, [(axis + 1) % 3, (axis + 2) % 3]])
    safe = in_safe_range(plane)
    if not _simple(plane, safe):
        if policy != "any":
            return "seen along its normal the loop crosses itself"
        # A loop bent far from any coordinate plane (a hole across a fold) can still be simple
        # seen along its own normal: take coordinates in that plane (rounded, so the
        # triangulation is only a choice, and its faces are tested exactly in 3-D after).
        plane = _in_own_plane(relative, normal / length)
        safe = in_safe_range(plane)
        if not _simple(plane, safe):
            return "seen along its normal the loop crosses itself"
        return _ear_clipping(plane, vertices, safe, has_edge), False
    return _ear_clipping(plane, vertices, safe, has_edge), True


def _in_own_plane(relative: np.ndarray, unit_normal: np.ndarray) -> np.ndarray:
    """``(k, 2)`` coordinates of points (relative to their centroid) in the plane normal to
    ``unit_normal``, in a right-handed frame (so the loop keeps its winding)."""
    helper = np.eye(3)[int(np.argmin(np.abs(unit_normal)))]
    u = np.cross(unit_normal, helper)
    u /= np.sqrt(u @ u)
    w = np.cross(unit_normal, u)
    return np.ascontiguousarray(np.stack([relative @ u, relative @ w], axis=1))


def _simple(plane: np.ndarray, safe: bool) -> bool:
    """Whether the closed polygon ``plane`` ``(k, 2)`` is simple: no two edges meet except
    consecutive ones at their shared corner (and those do not fold back on each other)."""
    k = len(plane)
    a, b = plane, np.roll(plane, -1, axis=0)
    after = np.roll(plane, -2, axis=0)
    # Consecutive edges a->b, b->after fold back when collinear and turning round.
    turn = orient2d(a, b, after, safe)
    back = ((b - a) * (after - b)).sum(axis=1) <= 0
    if ((turn == 0) & back).any():
        return False
    # Two closed edges meet only if their boxes do (closed, compared exactly): the pairs are
    # those whose boxes overlap, found by a sweep over the edges sorted by their lowest x, a
    # block of rows at a time (bounded temporaries, few calls). Every other pair of edges i < j
    # that are not consecutive (j >= i + 2, and not the first with the last) is disjoint.
    low, high = np.minimum(a, b), np.maximum(a, b)
    order = np.argsort(low[:, 0], kind="stable")
    starts = low[order, 0]
    # Sorted position p overlaps in x the positions p + 1 .. reach[p] - 1.
    reach = np.searchsorted(starts, high[order, 0], side="right")
    counts = np.maximum(reach - np.arange(k) - 1, 0)
    ends = np.cumsum(counts)
    begin = 0
    while begin < k:
        stop = max(int(np.searchsorted(ends, (ends[begin - 1] if begin else 0) + PAIRS, side="right")), begin + 1)
        stop = min(stop, k)
        number = counts[begin:stop]
        total = int(number.sum())
        if total:
            first = np.repeat(np.arange(begin, stop), number)
            offsets = np.arange(total) - np.repeat(np.cumsum(number) - number, number)
            i, j = order[first], order[first + 1 + offsets]
            i, j = np.minimum(i, j), np.maximum(i, j)
            keep = ((j >= i + 2) & ~((i == 0) & (j == k - 1))
                    & (low[i, 1] <= high[j, 1]) & (low[j, 1] <= high[i, 1]))
            i, j = i[keep], j[keep]
            if i.size and _segments_meet(a[i], b[i], a[j], b[j], safe).any():
                return False
        begin = stop
    return True


def _segments_meet(p: np.ndarray, q: np.ndarray, r: np.ndarray, s: np.ndarray, safe: bool) -> np.ndarray:
    """Whether each closed segment ``p[i] q[i]`` meets closed segment ``r[i] s[i]`` (``(n, 2)``
    each)."""
    d1, d2 = orient2d(p, q, r, safe), orient2d(p, q, s, safe)
    d3, d4 = orient2d(r, s, p, safe), orient2d(r, s, q, safe)
    proper = (d1 * d2 < 0) & (d3 * d4 < 0)

    def on(a, b, c):    # c on the closed segment a b, given the three are collinear
        return ((np.minimum(a[:, 0], b[:, 0]) <= c[:, 0]) & (c[:, 0] <= np.maximum(a[:, 0], b[:, 0]))
                & (np.minimum(a[:, 1], b[:, 1]) <= c[:, 1]) & (c[:, 1] <= np.maximum(a[:, 1], b[:, 1])))

    touch = (((d1 == 0) & on(p, q, r)) | ((d2 == 0) & on(p, q, s))
             | ((d3 == 0) & on(r, s, p)) | ((d4 == 0) & on(r, s, q)))
    return proper | touch


def _ear_clipping(plane: np.ndarray, vertices: np.ndarray, safe: bool, has_edge) -> np.ndarray | None:
    """Triangles ``(k - 2, 3)`` of vertex ids wound like the loop, or None when clipping gets
    stuck (every remaining ear would repeat an existing edge)."""
    plane = np.ascontiguousarray(plane, dtype=np.float64)
    k = len(plane)
    # The polygon's winding in the plane: the sign at its lowest corner (lexicographic), which
    # a simple polygon always turns strictly at.
    low = int(np.lexsort((plane[:, 1], plane[:, 0]))[0])
    sign = int(orient2d(plane[[low - 1]], plane[[low]], plane[[(low + 1) % k]], safe)[0])
    following = list(range(1, k)) + [0]
    before = [k - 1] + list(range(k - 1))
    alive = np.ones(k, dtype=bool)
    out: list[tuple[int, int, int]] = []
    added: set[tuple[int, int]] = set()

    # The corners sorted by x: a corner in an ear's closed triangle lies in its box (closed,
    # compared exactly), so only the alive corners of the box's x range and y range are tried.
    xs, ys = plane[:, 0].tolist(), plane[:, 1].tolist()
    by_x = np.argsort(plane[:, 0], kind="stable")
    sorted_x = plane[by_x, 0].tolist()
    order = by_x.tolist()
    column_y = plane[:, 1]
    living = [True] * k
    fast = compiled()

    def turn(u: int, v: int, w: int) -> int:
        # orient2d_about's float filter on Python floats (the same operations, so the same
        # sign where it decides); the exact test where it does not.
        if safe:
            left = (xs[u] - xs[w]) * (ys[v] - ys[w])
            right = (ys[u] - ys[w]) * (xs[v] - xs[w])
            det = left - right
            perm = abs(left) + abs(right)
            if not (abs(det) <= CCW_BOUND * perm and perm != 0):
                return (det > 0) - (det < 0)
        return int(orient2d_about(plane[u], plane[v], plane[[w]], safe)[0])

    def holds_corner(u: int, v: int, w: int, first: int, last: int) -> bool:
        """Whether an alive corner of sorted positions ``first..last - 1`` (but u, v, w) lies
        in the closed triangle u v w: one corner at a time for a few, as arrays for many (the
        same exact signs either way), or by the compiled kernels' float filter where it decides."""
        if fast is not None and safe:
            held = fast.ear_holds(plane, by_x, alive, sign, CCW_BOUND, u, v, w, first, last)
            if held >= 0:
                return held == 1
        lo_y, hi_y = min(ys[u], ys[v], ys[w]), max(ys[u], ys[v], ys[w])
        if last - first <= LOOPED:
            for c in order[first:last]:
                if (living[c] and lo_y <= ys[c] <= hi_y and c != u and c != v and c != w
                        and turn(u, v, c) * sign >= 0 and turn(v, w, c) * sign >= 0 and turn(w, u, c) * sign >= 0):
                    return True
            return False
        others = by_x[first:last]
        heights = column_y[others]
        others = others[alive[others] & (heights >= lo_y) & (heights <= hi_y)
                        & (others != u) & (others != v) & (others != w)]
        if others.size == 0:
            return False
        c = plane[others]
        # Inside the closed triangle: on the inner side of (or on) each edge; the corners
        # that fail one edge are not tried on the next.
        for x, y in ((u, v), (v, w), (w, u)):
            c = c[orient2d_about(plane[x], plane[y], c, safe) * sign >= 0]
            if c.size == 0:
                return False
        return True

    def ear(v: int) -> bool:
        u, w = before[v], following[v]
        if turn(u, v, w) != sign:
            return False
        first = bisect_left(sorted_x, min(xs[u], xs[v], xs[w]))
        last = bisect_right(sorted_x, max(xs[u], xs[v], xs[w]))
        if holds_corner(u, v, w, first, last):
            return False
        a, b = int(vertices[u]), int(vertices[w])
        return (min(a, b), max(a, b)) not in added and not has_edge(a, b)

    remaining = k
    v = 0
    stuck = 0
    while remaining > 3:
        if ear(v):
            u, w = before[v], following[v]
            out.append((int(vertices[u]), int(vertices[v]), int(vertices[w])))
            a, b = int(vertices[u]), int(vertices[w])
            added.add((min(a, b), max(a, b)))
            following[u], before[w] = w, u
            alive[v] = living[v] = False
            remaining -= 1
            stuck = 0
            v = u
        else:
            stuck += 1
            if stuck > remaining:
                return None
            v = following[v]
    u, w = before[v], following[v]
    if int(orient2d(plane[[u]], plane[[v]], plane[[w]], safe)[0]) != sign:
        return None
    out.append((int(vertices[u]), int(vertices[v]), int(vertices[w])))
    return np.array(out, dtype=np.int64)
