"""Inside test for triangle meshes: ray parity along one axis, over a 2-D grid of the faces.

For each query point a ray is cast along the axis ``k`` (the axis of the mesh's smallest
extent, so that the projected faces cover the widest area and rays cross the fewest faces),
both up and down. A point is inside a closed mesh when a ray crosses its surface an odd
number of times; parity, unlike the signed winding number, ignores the faces' orientation, so
it is right for an inward-wound or inconsistently wound closed mesh too.

Robustness at edges and vertices (a ray through a shared edge must count exactly once):

- Every projected edge is evaluated from its two endpoints in a canonical order (smaller
  endpoint first), so the two faces sharing an edge get exactly negated edge functions: the
  same floating-point operations on the same numbers. A point is therefore on one side of
  the edge for both faces, never inside both or neither.
- An edge function that is exactly zero is broken by simulation of simplicity: the point is
  treated as moved by ``(ε, ε²)`` in the projection plane, which can never lie on an edge
  line or a vertex, so rays through vertices are also counted once.

Open meshes degrade gracefully: the parities of the up and the down ray agree for a closed
mesh and may differ where a ray escapes through a hole; the returned indicator is their
mean, ``0``, ``0.5`` or ``1`` (an estimate of "how inside" the point is, in the spirit of the
generalised winding number).

Acceleration: the faces' projected bounding boxes are binned in a uniform 2-D grid
(compressed row storage), so each point tests only the faces of its own cell. Work is done
in chunks of point-face pairs so that memory stays bounded.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Point-face pairs processed per chunk (memory ~ 100 bytes per pair).
PAIR_CHUNK = 1 << 21
#: Cap on the (face, cell) entries of the grid; the grid is coarsened until it fits.
MAX_GRID_ENTRIES = 1 << 24


@dataclass(frozen=True)
class FaceGrid:
    """A mesh prepared for ``inside`` queries (built by ``face_grid``).

    Attributes
    ----------
    axis : int
        The ray axis.
    origin, scale : (3,) float64
        Points and faces are compared in ``(x - origin) / scale`` coordinates.
    lo : (2,) float64
        Lower corner of the grid in the projection plane.
    inv_cell : (2,) float64
        Cells per unit length along the two plane axes.
    shape : (2,) int
        Cells along the two plane axes.
    starts : (cells + 1,) int64
        Row pointers of the cell -> face lists.
    items : (entries,) int64
        Face indices, cell after cell.
    edges : (3, 5, n) float64
        Per edge (opposite vertex 0, 1, 2) and face: canonical start ``(u, v)``, direction
        ``(du, dv)`` and the orientation sign (+1 or -1) that makes it the face's edge
        (component-major, so that gathers read contiguous arrays).
    heights : (3, n) float64
        Ray-axis coordinate of each vertex.
    """

    axis: int
    origin: np.ndarray
    scale: np.ndarray
    lo: np.ndarray
    inv_cell: np.ndarray
    shape: tuple[int, int]
    starts: np.ndarray
    items: np.ndarray
    edges: np.ndarray
    heights: np.ndarray


def face_grid(triangles: np.ndarray, origin=None, scale=None, axis: int | None = None,
              cells_per_face: float = 4.0) -> FaceGrid:
    """Prepare ``triangles`` for ``inside``.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64
        Widened to float64 first.
    origin, scale : (3,) array_like, optional
        Local frame; default the centre and half-size of the bounding box (so a part far from
        the world origin keeps its resolution).
    axis : int, optional
        Ray axis; default the axis of the smallest extent.
    cells_per_face : float
        Grid cells per face (before coarsening).
    """
    tri = np.asarray(triangles, dtype=np.float64).reshape(-1, 3, 3)
    if len(tri):
        lo3, hi3 = tri.reshape(-1, 3).min(axis=0), tri.reshape(-1, 3).max(axis=0)
    else:
        lo3 = hi3 = np.zeros(3)
    if origin is None:
        origin = 0.5 * (lo3 + hi3)
    if scale is None:
        scale = 0.5 * (hi3 - lo3)
    origin = np.asarray(origin, dtype=np.float64)
    scale = np.asarray(scale, dtype=np.float64).copy()
    scale[~(scale > 0)] = 1.0
    local = (tri - origin) / scale
    if axis is None:
        axis = int(np.argmin(hi3 - lo3))
    plane = [i for i in range(3) if i != axis]
    uv = local[:, :, plane]                       # (n, 3, 2)
    # Faces whose projection has exactly zero area can never be crossed by a generic ray.
    area2 = ((uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1])
             - (uv[:, 1, 1] - uv[:, 0, 1]) * (uv[:, 2, 0] - uv[:, 0, 0]))
    keep = area2 != 0
    uv, heights = uv[keep], np.ascontiguousarray(local[keep][:, :, axis].T)
    edges = np.ascontiguousarray(_canonical_edges(uv).transpose(1, 2, 0))

    n = len(uv)
    if n:
        plo, phi = uv.reshape(-1, 2).min(axis=0), uv.reshape(-1, 2).max(axis=0)
    else:
        plo, phi = np.zeros(2), np.ones(2)
    extent = np.maximum(phi - plo, 1e-300)
    # Small meshes still get a fine grid: large faces then cost little per query point.
    target = max(1024.0, cells_per_face * n)
    while True:
        side = np.sqrt(extent[0] * extent[1] / target)
        shape = np.clip(np.ceil(extent / max(side, 1e-300)), 1, max(1, int(target))).astype(np.int64)
        while shape[0] * shape[1] > 4 * target + 4:
            shape = np.maximum(1, shape // 2)
        inv_cell = shape / extent
        fmin = _cell(uv.min(axis=1), plo, inv_cell, shape)
        fmax = _cell(uv.max(axis=1), plo, inv_cell, shape)
        span = fmax - fmin + 1
        entries = int((span[:, 0] * span[:, 1]).sum()) if n else 0
        if entries <= MAX_GRID_ENTRIES or target <= 1:
            break
        target /= 4
    starts, items = _bin_faces(fmin, span, shape)
    return FaceGrid(axis, origin, scale, plo, inv_cell, (int(shape[0]), int(shape[1])),
                    starts, items, edges, heights)


def _canonical_edges(uv: np.ndarray) -> np.ndarray:
    """``(n, 3, 5)``: for the edge opposite each vertex, canonical start, direction, sign."""
    out = np.empty((len(uv), 3, 5))
    for k in range(3):
        a, b = uv[:, (k + 1) % 3], uv[:, (k + 2) % 3]
        # Lexicographic order on (u, v) makes the shared edge of two faces identical.
        swap = (b[:, 0] < a[:, 0]) | ((b[:, 0] == a[:, 0]) & (b[:, 1] < a[:, 1]))
        start = np.where(swap[:, None], b, a)
        end = np.where(swap[:, None], a, b)
        out[:, k, 0:2] = start
        out[:, k, 2:4] = end - start
        out[:, k, 4] = np.where(swap, -1.0, 1.0)
    return out


def _cell(uv: np.ndarray, lo: np.ndarray, inv_cell: np.ndarray, shape) -> np.ndarray:
    """Grid cell of plane points; the same monotone formula for faces and queries, so a point
    inside a face's box always lands in one of the face's cells."""
    idx = np.floor((uv - lo) * inv_cell)
    return np.clip(idx, 0, np.asarray(shape) - 1).astype(np.int64)


def _bin_faces(fmin: np.ndarray, span: np.ndarray, shape) -> tuple[np.ndarray, np.ndarray]:
    """Compressed row storage of the faces overlapping each cell."""
    n = len(fmin)
    cells = int(shape[0]) * int(shape[1])
    if n == 0:
        return np.zeros(cells + 1, dtype=np.int64), np.zeros(0, dtype=np.int64)
    counts = span[:, 0] * span[:, 1]
    face = np.repeat(np.arange(n), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    local = np.arange(len(face)) - first
    w = span[face, 1]
    cu = fmin[face, 0] + local // w
    cv = fmin[face, 1] + local % w
    cell = cu * shape[1] + cv
    order = np.argsort(cell, kind="stable")
    starts = np.zeros(cells + 1, dtype=np.int64)
    np.cumsum(np.bincount(cell, minlength=cells), out=starts[1:])
    return starts, face[order]


def inside(grid: FaceGrid, points: np.ndarray) -> np.ndarray:
    """Inside indicator of ``points`` for the mesh in ``grid``.

    Parameters
    ----------
    grid : FaceGrid
    points : (m, 3) float64
        World coordinates.

    Returns
    -------
    (m,) float64
        1 inside, 0 outside a closed mesh (whatever its winding); 0.5 where the up and down
        rays disagree (only possible on an open mesh).
    """
    local = (np.asarray(points, dtype=np.float64).reshape(-1, 3) - grid.origin) / grid.scale
    return inside_local(grid, local)


def inside_local(grid: FaceGrid, local: np.ndarray) -> np.ndarray:
    """``inside`` for points already in the grid's local frame ``(x - origin) / scale``."""
    m = len(local)
    plane = [i for i in range(3) if i != grid.axis]
    uv = np.ascontiguousarray(local[:, plane].T)
    h = np.ascontiguousarray(local[:, grid.axis])
    cell = _cell(uv.T, grid.lo, grid.inv_cell, grid.shape)
    cell = cell[:, 0] * grid.shape[1] + cell[:, 1]
    begin = grid.starts[cell]
    counts = grid.starts[cell + 1] - begin
    up = np.zeros(m, dtype=np.int64)
    down = np.zeros(m, dtype=np.int64)
    # Chunk the points so that each chunk has at most PAIR_CHUNK point-face pairs.
    cum = np.cumsum(counts)
    start = 0
    while start < m:
        base = cum[start - 1] if start else 0
        stop = int(np.searchsorted(cum, base + PAIR_CHUNK, side="right"))
        stop = max(stop, start + 1)
        _count_crossings(grid, uv, h, begin, counts, start, min(stop, m), up, down)
        start = stop
    return 0.5 * ((up & 1) + (down & 1)).astype(np.float64)


def _edge_value(grid, k, face, pu, pv) -> np.ndarray:
    """Oriented edge function of edge ``k`` of ``face`` at ``(pu, pv)``, never exactly zero."""
    au, av, du, dv, sgn = (grid.edges[k, i][face] for i in range(5))
    val = du * (pv - av) - dv * (pu - au)
    zero = val == 0
    if zero.any():
        # Simulation of simplicity: p moved by (ε, ε²) gives -dv ε + du ε²; du > 0 whenever
        # dv == 0 on a canonical edge, so the tie never stays at zero.
        tie = np.where(dv[zero] != 0, -np.sign(dv[zero]), 1.0)
        val[zero] = tie * np.finfo(np.float64).tiny
    val *= sgn
    return val


def _count_crossings(grid, uv, h, begin, counts, start, stop, up, down) -> None:
    c = counts[start:stop]
    total = int(c.sum())
    if total == 0:
        return
    point = np.repeat(np.arange(start, stop), c)
    offset = np.arange(total) - np.repeat(np.cumsum(c) - c, c)
    face = grid.items[np.repeat(begin[start:stop], c) + offset]
    pu, pv = uv[0][point], uv[1][point]
    # Edge by edge, dropping pairs as soon as two edge functions disagree in sign (most
    # candidates from the grid cell are not crossed at all).
    w0 = _edge_value(grid, 0, face, pu, pv)
    w1 = _edge_value(grid, 1, face, pu, pv)
    keep = (w0 > 0) == (w1 > 0)
    point, face, pu, pv, w0, w1 = point[keep], face[keep], pu[keep], pv[keep], w0[keep], w1[keep]
    w2 = _edge_value(grid, 2, face, pu, pv)
    keep = (w0 > 0) == (w2 > 0)
    if not keep.any():
        return
    point, face, w0, w1, w2 = point[keep], face[keep], w0[keep], w1[keep], w2[keep]
    hp = h[point]
    # Barycentric height of the crossing relative to the point: sign(Σ w_i z_i / Σ w_i).
    num = (w0 * (grid.heights[0][face] - hp) + w1 * (grid.heights[1][face] - hp)
           + w2 * (grid.heights[2][face] - hp))
    above = (num > 0) == (w0 > 0)
    size = stop - start
    up[start:stop] += np.bincount(point[above] - start, minlength=size)
    down[start:stop] += np.bincount(point[~above] - start, minlength=size)
