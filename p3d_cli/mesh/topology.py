"""Topology of a triangle soup: edges, orientation, degenerate and duplicate faces, shells.

How vertices are matched
------------------------
Two corners are the same vertex when their coordinates are *exactly* equal (after widening
to float64; ``-0.0`` equals ``0.0``). Nothing is welded, snapped or merged within a
tolerance, so a seam whose two sides differ in the last bit counts as two boundary edges.
This is the rule of ``p3d_cli.mesh.closed`` and of ``p3d props``' ``closed`` flag, so every
p3d command agrees about the same file. Corners are grouped by a sort of hash keys and the
groups are confirmed by comparing coordinates exactly (``p3d_cli.mesh.vertices``).

Definitions
-----------
An edge is an unordered pair of distinct vertices used by some face side (a side whose two
ends coincide bounds nothing and is skipped, as in ``closed``).

- boundary edge: used by exactly one face;
- non-manifold edge: used by more than two faces;
- misoriented edge: used by exactly two faces that traverse it in the same direction;
- closed: at least one face, and every edge is used by exactly two faces in opposite
  directions (no boundary, non-manifold or misoriented edge);
- non-manifold vertex: a vertex whose faces form more than one fan joined across edges
  used by exactly two faces (two solids touching at a point); vertices on a non-manifold
  edge are not counted again here;
- zero-area face: the cross product of its two sides is exactly zero (decided exactly, with
  no tolerance: see ``p3d_cli.mesh.faces``; this includes every face with a repeated vertex);
- degenerate face: a zero-area face (repeated vertex or three collinear points);
- duplicate face: a face with the same three vertices as an earlier face, in any order or
  orientation; the earlier face is not counted;
- shell: a connected component of faces, two faces being connected when they share an
  edge (not merely a vertex: two cubes touching at a corner are two shells, and their
  shared corner a non-manifold vertex). A face whose three corners coincide has no edge
  and is a shell of its own.

Cost: a clean mesh (every edge used once each way) takes ``p3d_cli.mesh.paired``'s fast
path: one ``numpy.sort`` of ``3n`` packed 64-bit side keys, fans by pointer doubling, one
exact confirmation pass; so does a mesh whose other edges are all boundary edges (its layout
then lists the boundary sides alone, for ``p3d repair``: ``edges.lone_sides``). Any other
mesh takes the general path: one ``numpy.sort`` of ``3n``
packed 64-bit corner keys; everything else is a linear pass, a stable sort of already nearly
sorted keys, or a union-find of a few rounds. Both give the same report (the tests compare).
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.mesh.boundary import boundary_volume, sides_volume
from p3d_cli.mesh.boundary_sides import SIDE_BLOCK, unbalanced_of
from p3d_cli.mesh.closed import corner_hashes
from p3d_cli.mesh.edges import Edges, group_edges, lone_sides, next_corner
from p3d_cli.mesh.faces import duplicate_candidates, duplicate_faces, repeated_vertex_faces, zero_area_faces
from p3d_cli.mesh.fans import nonmanifold_vertices, vertex_sample_faces
from p3d_cli.mesh.layout import Layout
from p3d_cli.mesh.paired import Paired, paired_topology
from p3d_cli.mesh.report import SAMPLES, EdgeSample, Shell, TopologyReport, VertexSample
from p3d_cli.mesh.shells import LISTED_SHELLS, Components, components, shell_volumes, shells
from p3d_cli.mesh.vertices import corner_coords, group_corners

__all__ = ["Components", "EdgeSample", "LISTED_SHELLS", "SAMPLES", "Shell",
           "TopologyReport", "VertexSample", "components", "corner_vertex_ids",
           "topology", "topology_and_layout", "topology_of_blocks"]


def corner_vertex_ids(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact vertex ids of every corner, and the coordinates of each vertex.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64, finite

    Returns
    -------
    ids : (n, 3) int64
        Equal exactly when the corners' coordinates are equal (``-0.0 == 0.0``).
    points : (m, 3) float64
        Coordinates of vertex ``i`` at row ``i``.
    """
    triangles = np.asarray(triangles)
    n = len(triangles)
    found = group_corners(_array_blocks(triangles), n, hasher=_module_hashes)
    return found.ids.reshape(n, 3).astype(np.int64), found.points.astype(np.float64) + 0.0


def _module_hashes(cols: np.ndarray) -> np.ndarray:
    """``corner_hashes`` (looked up here, so that a test can replace it) as ``(3, k)``."""
    flat = np.ascontiguousarray(np.moveaxis(cols, 2, 0)).reshape(-1, 3)
    return np.asarray(corner_hashes(flat), dtype=np.uint64).reshape(-1, 3).T.copy()


def topology(triangles: np.ndarray) -> TopologyReport:
    """Edge, face and shell checks of a triangle soup (see the module docstring).

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64
        Finite corner coordinates (callers reject NaN and infinity first).

    Returns
    -------
    TopologyReport
    """
    triangles = np.asarray(triangles)
    return topology_of_blocks(_array_blocks(triangles), len(triangles))


def _array_blocks(triangles: np.ndarray):
    def blocks():
        for start in range(0, len(triangles), 1 << 14):
            yield triangles[start:start + (1 << 14)]
    return blocks


def topology_of_blocks(blocks, n: int, where: str | None = None) -> TopologyReport:
    """``topology`` of ``n`` triangles read (two or three times) from ``blocks()``.

    Parameters
    ----------
    blocks : callable
        Returns an iterator over ``(k, 3, 3)`` float arrays in file order.
    n : int
    where : str, optional
        The input's name: when given, a NaN or infinite coordinate raises ``InputError``.

    Raises
    ------
    RangeError
        The volume (or a shell's) is beyond float64: coordinates past about 1e100 (a
        volume of 1e300 and more), where an infinite or NaN volume would be a wrong number.
    """
    return topology_and_layout(blocks, n, where, edges=False)[0]


def topology_and_layout(blocks, n: int, where: str | None = None,
                        edges: bool = True) -> tuple[TopologyReport, Layout | None]:
    """``topology_of_blocks``, and the vertex ids, shells and edges it found (None for no faces),
    for the passes that follow (self-intersections, the shells' nesting, ``p3d repair``).

    ``edges``: whether the layout of a mesh with problem edges must hold them grouped
    (``Layout.edges``, which ``p3d repair`` reads): the general path's groups, or the boundary
    sides alone when the fast path took a mesh whose only problem edges are boundary edges
    (``edges.lone_sides``). Without, that layout's ``edges`` is None."""
    with np.errstate(over="ignore", invalid="ignore"):   # refused below, in one error
        report, layout = _topology_of_blocks(blocks, n, where, grouped=edges)
    if not all(math.isfinite(v) for v in [report.volume] + [s.volume for s in report.shell_list]):
        from p3d_cli.errors import RangeError

        raise RangeError(where or "mesh", "the signed volume overflows float64 (coordinates too large for "
                         "their cubes)", "scale the mesh into a larger unit (e.g. km instead of mm)")
    return report, layout


def _topology_of_blocks(blocks, n: int, where: str | None,
                        grouped: bool = False) -> tuple[TopologyReport, Layout | None]:
    if n == 0:
        return _empty_report(), None
    fast = paired_topology(blocks, n, where, boundary=True)
    if fast is not None and fast.boundary.size:
        return _open_report(blocks, n, fast, grouped)
    if fast is not None:
        layout = Layout(fast.ids, int(fast.ids.max()) + 1, fast.shells, fast.zero_area,
                        np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64))
        return _paired_report(blocks, n, fast), layout
    zero_area: list[np.ndarray] = []

    def per_block(first_face: int, cols: np.ndarray, block) -> None:
        zero_area.append(zero_area_faces(cols) + first_face)

    corners = group_corners(blocks, n, on_block=per_block, where=where)
    corners.points = None       # memory: the few sample points are read again at the end
    first_corner = corners.corner_at(corners.first[:-1]).astype(corners.ids.dtype)
    degree = np.diff(corners.first).astype(np.int32)
    edges = group_edges(corners)                        # frees the sorted corner keys
    m, corners.first = corners.count, None              # not needed any more: memory
    edges.forward = None
    ids = corners.ids
    nonmanifold = nonmanifold_vertices(ids, m, first_corner, degree, edges)
    del first_corner, degree
    # The sides were unpacked into the sorted keys' buffer, half of which held the twins:
    # compact them and let the buffer go before the shells' union-find (peak memory).
    edges.spare = None
    edges.side = edges.side.copy()
    found = shells(n, edges)
    faces = ids.reshape(n, 3)
    repeated = repeated_vertex_faces(faces)
    duplicates = duplicate_faces(faces, _duplicate_candidates(n, edges, found, repeated))
    zero = np.concatenate(zero_area) if zero_area else np.zeros(0, dtype=np.int64)
    layout = Layout(ids, m, found, zero, _crowded(edges, ids), _open_shells(edges, found), edges, duplicates)
    volume = _volume(blocks, corners, edges, ids)
    edge_samples = [_edge_samples(edges, groups, ids)
                    for groups in (edges.boundary, edges.nonmanifold, edges.misoriented)]
    vertex_samples = [int(v) for v in nonmanifold[:SAMPLES]]
    points = _sample_points(blocks, ids, [v for samples in edge_samples for _, a, b in samples
                                          for v in (a, b)] + vertex_samples)
    lone, nonmanifold_edges, misoriented = (
        tuple(EdgeSample(faces, (points[a], points[b])) for faces, a, b in samples)
        for samples in edge_samples)
    report = TopologyReport(
        faces=n, vertices=m, edges=edges.count,
        boundary_edges=int(edges.boundary.size), nonmanifold_edges=int(edges.nonmanifold.size),
        misoriented_edges=int(edges.misoriented.size), nonmanifold_vertices=int(nonmanifold.size),
        zero_area_faces=int(zero.size), faces_with_repeated_vertex=int(repeated.size),
        degenerate_faces=int(zero.size), duplicate_faces=int(duplicates.shape[0]),
        shells=int(found.count), shell_list=tuple(shell_volumes(blocks, n, found, volume)),
        volume=volume, boundary_edge_samples=lone,
        nonmanifold_edge_samples=nonmanifold_edges, misoriented_edge_samples=misoriented,
        nonmanifold_vertex_samples=tuple(VertexSample(vertex_sample_faces(ids, v), points[v])
                                         for v in vertex_samples),
        degenerate_face_samples=tuple(int(f) for f in zero[:SAMPLES]),
        duplicate_face_samples=tuple((int(a), int(b)) for a, b in duplicates[:SAMPLES]),
    )
    return report, layout


def _crowded(edges: Edges, ids: np.ndarray) -> np.ndarray:
    """Vertex ids ``(e, 2)`` of the edges used by more than two faces."""
    side = edges.side[edges.starts[edges.nonmanifold]].astype(np.int64)
    ends = np.stack([ids[side], ids[next_corner(side)]], axis=1).astype(np.int64)
    return np.sort(ends, axis=1)


def _open_shells(edges: Edges, found: Components) -> np.ndarray:
    """The shells that hold a boundary, non-manifold or misoriented edge."""
    groups = _problem_groups(edges)
    if groups.size == 0:
        return np.zeros(0, dtype=np.int64)
    return np.unique(found.labels[edges.side[_group_sides(edges, groups)] // 3]).astype(np.int64)


def _problem_groups(edges: Edges) -> np.ndarray:
    """The edge groups that are not one side each way: boundary, non-manifold, misoriented."""
    return np.concatenate([edges.boundary, edges.nonmanifold, edges.misoriented])


def _group_sides(edges: Edges, groups: np.ndarray) -> np.ndarray:
    """Positions in ``edges.side`` of every side of the given groups, group by group."""
    counts = edges.counts[groups].astype(np.int64)
    sides = np.repeat(edges.starts[groups].astype(np.int64), counts)
    sides += np.arange(sides.size) - np.repeat(np.cumsum(counts) - counts, counts)
    return sides


def _paired_report(blocks, n: int, fast: Paired) -> TopologyReport:
    """The report of a soup whose every edge is used once each way (``p3d_cli.mesh.paired``):
    no boundary, non-manifold or misoriented edge, no repeated vertex."""
    ids = fast.ids
    faces = ids.reshape(n, 3)
    found = fast.shells
    small = np.bincount(found.labels, minlength=found.count) <= 2   # see _duplicate_candidates
    duplicates = duplicate_faces(faces, np.flatnonzero(small[found.labels]))
    vertex_samples = [int(v) for v in fast.nonmanifold[:SAMPLES]]
    points = _sample_points(blocks, ids, vertex_samples)
    zero = fast.zero_area
    return TopologyReport(
        faces=n, vertices=fast.vertices, edges=3 * n // 2, boundary_edges=0, nonmanifold_edges=0,
        misoriented_edges=0, nonmanifold_vertices=int(fast.nonmanifold.size),
        zero_area_faces=int(zero.size), faces_with_repeated_vertex=0, degenerate_faces=int(zero.size),
        duplicate_faces=int(duplicates.shape[0]), shells=int(found.count),
        shell_list=tuple(shell_volumes(blocks, n, found, fast.volume)), volume=fast.volume,
        nonmanifold_vertex_samples=tuple(VertexSample(vertex_sample_faces(ids, v), points[v])
                                         for v in vertex_samples),
        degenerate_face_samples=tuple(int(f) for f in zero[:SAMPLES]),
        duplicate_face_samples=tuple((int(a), int(b)) for a, b in duplicates[:SAMPLES]),
    )


def _open_report(blocks, n: int, fast: Paired, edges: bool = False) -> tuple[TopologyReport, Layout]:
    """The report and layout of a soup whose every edge is used once each way or once (a
    boundary edge: ``fast.boundary``), no repeated vertex: the general path's, from the fast
    path's findings (the layout's ``edges``: the boundary sides alone when asked, else None)."""
    ids = fast.ids
    faces = ids.reshape(n, 3)
    found = fast.shells
    lone = fast.boundary
    # No edge used more than twice: a duplicate and its face are a shell of two (see
    # _duplicate_candidates).
    small = np.bincount(found.labels, minlength=found.count) <= 2
    duplicates = duplicate_faces(faces, np.flatnonzero(small[found.labels]))
    volume = _with_boundary(blocks, fast.sums, lone, next_corner(lone), 3 * n)
    vertex_samples = [int(v) for v in fast.nonmanifold[:SAMPLES]]
    points = _sample_points(blocks, ids, vertex_samples)
    zero = fast.zero_area
    open_shells = np.unique(found.labels[lone // 3]).astype(np.int64)
    layout = Layout(ids, int(ids.max()) + 1, found, zero, np.zeros((0, 2), dtype=np.int64), open_shells,
                    lone_sides(lone) if edges else None)
    report = TopologyReport(
        faces=n, vertices=fast.vertices, edges=(3 * n + lone.size) // 2, boundary_edges=int(lone.size),
        nonmanifold_edges=0, misoriented_edges=0, nonmanifold_vertices=int(fast.nonmanifold.size),
        zero_area_faces=int(zero.size), faces_with_repeated_vertex=0, degenerate_faces=int(zero.size),
        duplicate_faces=int(duplicates.shape[0]), shells=int(found.count),
        shell_list=tuple(shell_volumes(blocks, n, found, volume)), volume=volume,
        boundary_edge_samples=_lone_samples(blocks, lone),
        nonmanifold_vertex_samples=tuple(VertexSample(vertex_sample_faces(ids, v), points[v])
                                         for v in vertex_samples),
        degenerate_face_samples=tuple(int(f) for f in zero[:SAMPLES]),
        duplicate_face_samples=tuple((int(a), int(b)) for a, b in duplicates[:SAMPLES]),
    )
    return report, layout


def _lone_samples(blocks, lone: np.ndarray) -> tuple[EdgeSample, ...]:
    """``_edge_samples`` of the boundary sides ``lone`` (ascending): the first ``SAMPLES`` in
    file order, the sides of one face in the general path's edge order, each edge's ends in
    its vertex order (full corner hash, then coordinates: ``p3d_cli.mesh.vertices``)."""
    some = lone[:3 * SAMPLES]   # whole faces: the first SAMPLES faces' sides at least
    ends = corner_coords(blocks, np.concatenate([some, next_corner(some)]))
    hashes = corner_hashes(ends)
    order = np.lexsort((ends[:, 2], ends[:, 1], ends[:, 0], hashes))
    new = np.ones(order.size, dtype=bool)
    new[1:] = (hashes[order][1:] != hashes[order][:-1]) | (ends[order][1:] != ends[order][:-1]).any(axis=1)
    rank = np.empty(order.size, dtype=np.int64)
    rank[order] = np.cumsum(new) - 1          # equal points, equal ranks: the vertex order
    k = some.size
    swap = rank[:k] > rank[k:]
    lo = np.where(swap, np.arange(k) + k, np.arange(k))
    hi = np.where(swap, np.arange(k), np.arange(k) + k)
    out = []
    for i in np.lexsort((rank[hi], rank[lo], some // 3))[:SAMPLES]:
        a, b = ends[lo[i]], ends[hi[i]]
        out.append(EdgeSample((int(some[i] // 3),), ((float(a[0]), float(a[1]), float(a[2])),
                                                     (float(b[0]), float(b[1]), float(b[2])))))
    return tuple(out)


def _volume(blocks, corners, edges: Edges, ids: np.ndarray) -> float:
    """The signed volume ``p3d props`` reports for the same triangles (one convention,
    docs/method.md, "Open and non-manifold meshes"): the local sums when every edge cancels,
    plus the net boundary's exact volume term when some does not (``p3d_cli.mesh.boundary``).

    The edges whose two directions are not used equally often are found from the exact
    edges at hand; their sides are those ``boundary_sides.unbalanced_sides`` reads for ``p3d props``
    (the sides of the unbalanced edge keys), and their exact term is the same number. A soup,
    where ``props`` reads every side instead, takes ``props``' own road."""
    groups = _problem_groups(edges)
    if groups.size == 0:
        return corners.volume                       # closed: nothing to add
    at = _group_sides(edges, groups)
    side = edges.side[at].astype(np.int64)
    after = next_corner(side)
    step = np.where(ids[side] < ids[after], 1, -1)
    counts = edges.counts[groups].astype(np.int64)
    net = np.add.reduceat(step, np.cumsum(counts) - counts)
    odd = np.repeat(net != 0, counts)
    if not odd.any():
        return corners.volume                       # non-manifold but bounding
    return _with_boundary(blocks, corners.volume_sums, side[odd], after[odd], edges.side.size)


def _with_boundary(blocks, sums, side: np.ndarray, after: np.ndarray, sides: int) -> float:
    """The volume of the local ``sums`` plus the exact term of the unbalanced sides (corner
    ``side`` to corner ``after``; any order), of ``sides`` sides in all: read from these sides
    when they are at most half of all, else by ``p3d props``' own road."""
    chosen = side.size
    if 2 * chosen <= sides:
        ends = corner_coords(blocks, np.concatenate([side, after]))
        start, end = ends[:chosen], ends[chosen:]
        six_volume, _ = sides_volume(((np.ascontiguousarray(start[lo:lo + SIDE_BLOCK].T),
                                       np.ascontiguousarray(end[lo:lo + SIDE_BLOCK].T))
                                      for lo in range(0, chosen, SIDE_BLOCK)), sums.origin)
        return sums.volume(six_volume)
    unbalanced = unbalanced_of(blocks)
    if unbalanced.ids.size == 0:
        return sums.volume()                        # non-manifold but bounding
    six_volume, _ = boundary_volume(blocks(), unbalanced, sums.origin)
    return sums.volume(six_volume)


def _duplicate_candidates(n: int, edges: Edges, found, repeated: np.ndarray) -> np.ndarray:
    """The faces that can have a duplicate (``faces.duplicate_candidates``), cheaper when
    no edge is used more than twice: a face and its duplicate then share all three edges
    and nothing else, a shell of two faces (point faces, and faces whose one edge is used
    by their own two sides, are shells of one). A face with an edge used once (a boundary)
    has no duplicate, which would use that edge too; its shell may be of any size."""
    if edges.count and (edges.counts <= 2).all():
        small = np.bincount(found.labels, minlength=found.count) <= 2
        return np.flatnonzero(small[found.labels])
    return duplicate_candidates(n, edges.side, edges.starts, edges.counts, repeated)


def _edge_samples(edges: Edges, groups: np.ndarray, ids: np.ndarray) -> list:
    """``(faces, lo vertex, hi vertex)`` of the first ``SAMPLES`` problem edges in file order."""
    out = []
    # The problems met first in file order (each group's first side is its lowest face).
    first = np.argsort(edges.side[edges.starts[groups]] // 3, kind="stable")[:SAMPLES]
    for g in groups[first]:
        s, c = int(edges.starts[g]), int(edges.counts[g])
        faces = tuple(int(f) for f in edges.side[s:s + c] // 3)
        side = np.int64(edges.side[s])
        a, b = int(ids[side]), int(ids[next_corner(side)])
        out.append((faces, min(a, b), max(a, b)))
    return out


def _sample_points(blocks, ids: np.ndarray, vertices: list) -> dict:
    """Coordinates of the given vertices (``-0.0`` as ``0.0``), from one more pass if any."""
    if not vertices:
        return {}     # and numpy.unique not called: its first call imports numpy.ma (~13 ms)
    wanted = np.unique(np.asarray(vertices, dtype=np.int64))
    hit = np.flatnonzero(np.isin(ids, wanted))
    _, first = np.unique(ids[hit], return_index=True)    # each vertex's first corner
    coords = corner_coords(blocks, hit[first])
    return {int(v): (float(x), float(y), float(z)) for v, (x, y, z) in zip(wanted, coords)}


def _empty_report() -> TopologyReport:
    return TopologyReport(faces=0, vertices=0, edges=0, boundary_edges=0, nonmanifold_edges=0,
                          misoriented_edges=0, nonmanifold_vertices=0, zero_area_faces=0,
                          faces_with_repeated_vertex=0, degenerate_faces=0, duplicate_faces=0,
                          shells=0, shell_list=(), volume=0.0)
