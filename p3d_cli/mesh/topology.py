"""Topology of a triangle soup: edges, orientation, degenerate and duplicate faces, shells.

How vertices are matched
------------------------
Two corners are the same vertex when their coordinates are *exactly* equal (after widening
to float64; ``-0.0`` equals ``0.0``). Nothing is welded, snapped or merged within a
tolerance, so a seam whose two sides differ in the last bit counts as two boundary edges.
This is the rule of ``p3d_cli.mesh.closed`` and of ``p3d props``' ``closed`` flag, so every
p3d command agrees about the same file (USERS.md, "Closed depends on vertex merging").
Corners are hashed with ``closed.corner_hashes`` and the hash ids are confirmed exactly;
on a (64-bit) collision the exact ``closed.vertex_ids`` is used instead.

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
- zero-area face: the cross product of its two sides is exactly zero in float64 (no
  tolerance; this includes every face with a repeated vertex);
- degenerate face: a zero-area face (repeated vertex or three collinear points);
- duplicate face: a face with the same three vertices as an earlier face, in any order or
  orientation; the earlier face is not counted;
- shell: a connected component of faces, two faces being connected when they share an
  edge (not merely a vertex: two cubes touching at a corner are two shells, and their
  shared corner a non-manifold vertex). A face whose three corners coincide has no edge
  and is a shell of its own.

Every step is a sort or a linear pass over the ``3n`` face sides: the cost is O(n log n).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.closed import corner_hashes, vertex_ids
from p3d_cli.mesh.integrals import triangle_moments

#: Sample locations kept per kind of problem.
SAMPLES = 5
#: Shells listed individually (largest first); more are counted but not listed.
LISTED_SHELLS = 100


@dataclass(frozen=True)
class EdgeSample:
    """One problem edge: its two end points and the faces that use it.

    Attributes
    ----------
    faces : tuple of int
        Indices of the faces using the edge (0-based, in file order).
    points : ((3,), (3,)) tuple of float tuples
        The edge's two end points.
    """

    faces: tuple[int, ...]
    points: tuple[tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True)
class VertexSample:
    """One non-manifold vertex: where it is and some faces around it."""

    faces: tuple[int, ...]
    point: tuple[float, float, float]


@dataclass(frozen=True)
class Shell:
    """One connected shell.

    Attributes
    ----------
    faces : int
        Number of faces in the shell.
    first_face : int
        Its lowest face index (to find it in the file).
    volume : float
        Signed volume enclosed by the shell's faces (negative when wound inward; an inner
        cavity of a solid is a negative shell).
    """

    faces: int
    first_face: int
    volume: float


@dataclass(frozen=True)
class TopologyReport:
    """What ``topology`` found in a triangle soup.

    Counts are exact; each ``*_samples`` tuple holds at most ``SAMPLES`` locations. Face
    indices are 0-based positions in the input (file order, polygons split into fans).
    ``shells`` counts every shell; ``shell_list`` holds at most ``LISTED_SHELLS`` of them,
    largest first (ties by first face).
    """

    faces: int
    vertices: int
    edges: int
    boundary_edges: int
    nonmanifold_edges: int
    misoriented_edges: int
    nonmanifold_vertices: int
    zero_area_faces: int
    faces_with_repeated_vertex: int
    degenerate_faces: int
    duplicate_faces: int
    shells: int
    shell_list: tuple[Shell, ...]
    volume: float
    boundary_edge_samples: tuple[EdgeSample, ...] = ()
    nonmanifold_edge_samples: tuple[EdgeSample, ...] = ()
    misoriented_edge_samples: tuple[EdgeSample, ...] = ()
    nonmanifold_vertex_samples: tuple[VertexSample, ...] = ()
    degenerate_face_samples: tuple[int, ...] = ()
    duplicate_face_samples: tuple[tuple[int, int], ...] = ()

    @property
    def closed(self) -> bool:
        return (self.faces > 0 and self.edges > 0 and self.boundary_edges == 0
                and self.nonmanifold_edges == 0 and self.misoriented_edges == 0)

    @property
    def oriented(self) -> bool:
        return self.misoriented_edges == 0

    @property
    def manifold(self) -> bool:
        return self.nonmanifold_edges == 0 and self.nonmanifold_vertices == 0


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
    n = len(triangles)
    coords = np.asarray(triangles, dtype=np.float64).reshape(-1, 3) + 0.0
    hashes = corner_hashes(coords)
    _, first, inverse = np.unique(hashes, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    points = coords[first]
    # The 64-bit hash is only a fast key: confirm that equal hashes mean equal coordinates.
    if not np.array_equal(points[inverse], coords):
        inverse = vertex_ids(coords)
        points = np.zeros((int(inverse.max()) + 1 if inverse.size else 0, 3))
        points[inverse] = coords
    return inverse.reshape(n, 3).astype(np.int64), points


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
    n = len(triangles)
    ids, points = corner_vertex_ids(triangles)
    edges = _edges(ids)
    faces = _faces(triangles, ids)
    shells, vertex_fans = _connectivity(n, ids, edges)
    volume = float(triangle_moments(triangles).volume) if n else 0.0
    shell_list = tuple(_shell_volumes(triangles, shells, volume))
    nonmanifold_vertices, vertex_samples = vertex_fans
    return TopologyReport(
        faces=n,
        vertices=len(points),
        edges=edges.count,
        boundary_edges=int(edges.boundary.size),
        nonmanifold_edges=int(edges.nonmanifold.size),
        misoriented_edges=int(edges.misoriented.size),
        nonmanifold_vertices=nonmanifold_vertices,
        zero_area_faces=int(faces.zero_area.size),
        faces_with_repeated_vertex=int(faces.repeated.size),
        degenerate_faces=int(faces.zero_area.size),
        duplicate_faces=int(faces.duplicates.shape[0]),
        shells=int(shells.count),
        shell_list=shell_list,
        volume=volume,
        boundary_edge_samples=_edge_samples(edges, edges.boundary, points),
        nonmanifold_edge_samples=_edge_samples(edges, edges.nonmanifold, points),
        misoriented_edge_samples=_edge_samples(edges, edges.misoriented, points),
        nonmanifold_vertex_samples=tuple(
            VertexSample(tuple(faces_), _point(points[v])) for v, faces_ in vertex_samples),
        degenerate_face_samples=tuple(int(f) for f in faces.zero_area[:SAMPLES]),
        duplicate_face_samples=tuple((int(a), int(b)) for a, b in faces.duplicates[:SAMPLES]),
    )


# --- edges -------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Edges:
    """Face sides sorted by undirected edge, and the groups they form.

    ``face``, ``slot``, ``lo``, ``hi``, ``forward`` are per side (sorted by edge); ``starts``
    and ``counts`` delimit the groups (one per undirected edge); the last three hold group
    numbers.
    """

    face: np.ndarray
    slot: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    forward: np.ndarray
    starts: np.ndarray
    counts: np.ndarray
    boundary: np.ndarray
    nonmanifold: np.ndarray
    misoriented: np.ndarray

    @property
    def count(self) -> int:
        return int(self.starts.size)


def _edges(ids: np.ndarray) -> _Edges:
    n = len(ids)
    start = ids.reshape(-1)
    end = ids[:, [1, 2, 0]].reshape(-1)
    face = np.repeat(np.arange(n, dtype=np.int64), 3)
    slot = np.tile(np.arange(3, dtype=np.int8), n)
    keep = start != end  # a side from a point to itself bounds nothing
    start, end, face, slot = start[keep], end[keep], face[keep], slot[keep]
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    forward = start < end
    # One key per undirected edge; vertex ids are < 3n, so the product fits in int64 for any
    # mesh below ~10^9 faces. A stable sort keeps each edge's faces in file order.
    key = lo * (int(ids.max()) + 1 if ids.size else 1) + hi
    order = np.argsort(key, kind="stable")
    key, face, slot, lo, hi, forward = (a[order] for a in (key, face, slot, lo, hi, forward))
    if key.size:
        starts = np.flatnonzero(np.concatenate(([True], key[1:] != key[:-1])))
    else:
        starts = np.zeros(0, dtype=np.int64)
    counts = np.diff(np.append(starts, key.size))
    pairs = np.flatnonzero(counts == 2)
    same_way = forward[starts[pairs]] == forward[starts[pairs] + 1]
    return _Edges(face, slot, lo, hi, forward, starts, counts,
                  boundary=np.flatnonzero(counts == 1),
                  nonmanifold=np.flatnonzero(counts > 2),
                  misoriented=pairs[same_way])


def _edge_samples(edges: _Edges, groups: np.ndarray, points: np.ndarray) -> tuple[EdgeSample, ...]:
    out = []
    # The problems met first in file order (each group's first side is its lowest face).
    first = np.argsort(edges.face[edges.starts[groups]], kind="stable")[:SAMPLES]
    for g in groups[first]:
        s, c = int(edges.starts[g]), int(edges.counts[g])
        faces = tuple(int(f) for f in edges.face[s:s + c])
        out.append(EdgeSample(faces, (_point(points[edges.lo[s]]), _point(points[edges.hi[s]]))))
    return tuple(out)


def _point(p) -> tuple[float, float, float]:
    return (float(p[0]), float(p[1]), float(p[2]))


# --- faces -------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Faces:
    zero_area: np.ndarray  # face indices, ascending
    repeated: np.ndarray  # face indices, ascending
    duplicates: np.ndarray  # (k, 2): (first face, later duplicate), by later face


def _faces(triangles: np.ndarray, ids: np.ndarray) -> _Faces:
    repeated = np.flatnonzero((ids[:, 0] == ids[:, 1]) | (ids[:, 1] == ids[:, 2])
                              | (ids[:, 2] == ids[:, 0]))
    # Exactly zero in float64, no tolerance: a sliver with a tiny but non-zero area is kept.
    # Equal corners give exactly zero sides, so every face with a repeated vertex is here too.
    t = np.asarray(triangles, dtype=np.float64)
    cross = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    zero_area = np.flatnonzero(~cross.any(axis=1))
    # Same vertex set in any order: sort each face's ids, then sort the faces.
    key = np.sort(ids, axis=1)
    order = np.lexsort((np.arange(len(ids)), key[:, 2], key[:, 1], key[:, 0]))
    sorted_key = key[order]
    same = (sorted_key[1:] == sorted_key[:-1]).all(axis=1) if len(ids) else np.zeros(0, bool)
    new_group = np.concatenate(([True], ~same)) if len(ids) else np.zeros(0, bool)
    first_of_group = order[np.flatnonzero(new_group)]
    group = np.cumsum(new_group) - 1
    dup_pos = np.flatnonzero(~new_group)
    duplicates = np.stack([first_of_group[group[dup_pos]], order[dup_pos]], axis=1) \
        if dup_pos.size else np.zeros((0, 2), dtype=np.int64)
    duplicates = duplicates[np.argsort(duplicates[:, 1], kind="stable")]
    return _Faces(zero_area, repeated, duplicates)


# --- shells and vertex fans: connected components --------------------------------------------


@dataclass(frozen=True)
class _Components:
    labels: np.ndarray  # (n,) int64, 0..count-1, numbered by first member
    count: int


def components(size: int, a: np.ndarray, b: np.ndarray) -> _Components:
    """Connected components of a graph on ``size`` nodes with edges ``a[i] -- b[i]``.

    Vectorised union-find: each round hooks the larger root of every still-separate edge
    onto the smaller (``np.minimum.at``), then compresses paths by pointer jumping until
    every node points at its root. Every component with an unmerged edge merges with at
    least one other in a round, so there are O(log n) rounds of O(n + e) work each.

    Parameters
    ----------
    size : int
    a, b : (e,) int64

    Returns
    -------
    _Components
        Labels numbered in order of each component's smallest node.
    """
    parent = np.arange(size, dtype=np.int64)
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    while a.size:
        ra, rb = parent[a], parent[b]
        apart = ra != rb
        if not apart.any():
            break
        a, b, ra, rb = a[apart], b[apart], ra[apart], rb[apart]
        np.minimum.at(parent, np.maximum(ra, rb), np.minimum(ra, rb))
        while True:  # pointer jumping: parents only ever decrease, so this ends
            jumped = parent[parent]
            if np.array_equal(jumped, parent):
                break
            parent = jumped
    # Roots are the smallest node of their component, so unique() numbers by first member.
    roots, labels = np.unique(parent, return_inverse=True)
    return _Components(labels.reshape(-1), int(roots.size))


def _connectivity(n: int, ids: np.ndarray, edges: _Edges):
    """Shells (faces joined across shared edges) and non-manifold vertices (corner fans)."""
    # Shells: join consecutive sides of each edge group (sides are sorted by edge).
    same_edge = np.zeros(edges.face.size, dtype=bool)
    if edges.face.size:
        same_edge[1:] = (edges.lo[1:] == edges.lo[:-1]) & (edges.hi[1:] == edges.hi[:-1])
    later = np.flatnonzero(same_edge)
    shells = components(n, edges.face[later - 1], edges.face[later])

    # Vertex fans: corners (3 per face) at the same vertex are joined when their faces meet
    # across an edge used by exactly two faces, and within a face when two of its corners
    # coincide (a degenerate face). A manifold vertex then has one fan of corners.
    corner_vertex = ids.reshape(-1)
    pairs = edges.starts[edges.counts == 2]
    s1, s2 = pairs, pairs + 1

    def corner_at(side, vertex):
        # The side runs from corner `slot` to corner `slot + 1` of its face.
        slot = edges.slot[side].astype(np.int64)
        start_vertex = corner_vertex[3 * edges.face[side] + slot]
        return 3 * edges.face[side] + np.where(start_vertex == vertex, slot, (slot + 1) % 3)

    lo, hi = edges.lo[s1], edges.hi[s1]
    a = [corner_at(s1, lo), corner_at(s1, hi)]
    b = [corner_at(s2, lo), corner_at(s2, hi)]
    faces3 = np.arange(n, dtype=np.int64) * 3
    for i, j in ((0, 1), (1, 2), (2, 0)):
        twin = np.flatnonzero(ids[:, i] == ids[:, j])
        a.append(faces3[twin] + i)
        b.append(faces3[twin] + j)
    fans = components(3 * n, np.concatenate(a), np.concatenate(b))
    # Corners of faces with three equal corners touch nothing: leave them out of the count.
    live = ~np.repeat((ids[:, 0] == ids[:, 1]) & (ids[:, 1] == ids[:, 2]), 3)
    # Vertices on a non-manifold edge are reported through that edge already.
    on_bad_edge = np.zeros(int(ids.max()) + 1 if ids.size else 0, dtype=bool)
    if edges.nonmanifold.size:
        sides = np.repeat(edges.counts > 2, edges.counts)  # per side: is its edge non-manifold
        on_bad_edge[edges.lo[sides]] = True
        on_bad_edge[edges.hi[sides]] = True
    # Distinct (vertex, fan) pairs as one int64 key each: fans number fewer than 3n.
    pair_key = np.unique(corner_vertex[live] * (3 * n) + fans.labels[live])
    fans_per_vertex = np.bincount(pair_key // (3 * n), minlength=on_bad_edge.size)
    nonmanifold = np.flatnonzero((fans_per_vertex > 1) & ~on_bad_edge)
    samples = []
    for v in nonmanifold[:SAMPLES]:
        faces = np.unique(np.flatnonzero((corner_vertex == v) & live) // 3)[:8]
        samples.append((int(v), tuple(int(f) for f in faces)))
    return shells, (int(nonmanifold.size), samples)


def _shell_volumes(triangles: np.ndarray, shells: _Components, volume: float) -> list[Shell]:
    """The ``LISTED_SHELLS`` largest shells with their signed volumes (largest first)."""
    if shells.count == 0:
        return []
    if shells.count == 1:  # the common case: the whole mesh, whose volume is known
        return [Shell(len(triangles), 0, volume)]
    sizes = np.bincount(shells.labels, minlength=shells.count)
    # Labels are numbered by first face, so a stable sort by size keeps ties in file order.
    chosen = np.argsort(-sizes, kind="stable")[:LISTED_SHELLS]
    order = np.argsort(shells.labels, kind="stable")
    bounds = np.concatenate(([0], np.cumsum(sizes)))
    out = []
    for label in chosen:
        members = order[bounds[label]:bounds[label + 1]]
        volume = triangle_moments(triangles[members]).volume
        out.append(Shell(int(sizes[label]), int(members[0]), float(volume)))
    return out


# --- verdicts --------------------------------------------------------------------------------

#: The checks ``p3d check --require`` can ask for, and what each needs.
CHECKS = {
    "closed": "every edge used by exactly two faces, in opposite directions",
    "oriented": "no edge used twice in the same direction",
    "outward": "positive total signed volume (faces wound counter-clockwise seen from outside)",
    "manifold": "no edge used by more than two faces, no vertex joining separate fans of faces",
    "no-degenerate": "no face with zero area or a repeated vertex",
    "no-duplicate": "no two faces with the same three vertices",
}


def passes(report: TopologyReport, check: str) -> bool:
    """Whether ``report`` passes the named check (a key of ``CHECKS``)."""
    if check == "closed":
        return report.closed
    if check == "oriented":
        return report.oriented
    if check == "outward":
        return report.volume > 0
    if check == "manifold":
        return report.manifold
    if check == "no-degenerate":
        return report.degenerate_faces == 0
    if check == "no-duplicate":
        return report.duplicate_faces == 0
    raise KeyError(check)


@dataclass(frozen=True)
class CheckResult:
    """One mesh's verdict.

    Attributes
    ----------
    source : str
    format : str
    report : TopologyReport
    required : tuple of str
        The checks asked for (keys of ``CHECKS``).
    failed : tuple of str
        The required checks that failed, then ``min-volume`` / ``max-faces`` if a limit was
        broken, then ``NAME:CHECK`` for each check an object of a multi-object file failed.
    parts : tuple of (str, CheckResult)
        For a file of several objects (glTF nodes, 3MF build items), each object's verdict.
    """

    source: str
    format: str
    report: TopologyReport
    required: tuple[str, ...]
    failed: tuple[str, ...]
    parts: tuple = ()

    @property
    def ok(self) -> bool:
        return not self.failed


def check_source(mesh, source: str, required=tuple(CHECKS), min_volume: float | None = None,
                 max_faces: int | None = None) -> CheckResult:
    """Check a loaded mesh against the required checks and limits.

    Parameters
    ----------
    mesh : p3d_cli.io.MeshSource
    source : str
        The input's name (``-`` for standard input).
    required : iterable of str
        Keys of ``CHECKS``.
    min_volume : float, optional
        Fail when the total signed volume is below this.
    max_faces : int, optional
        Fail when the mesh has more faces than this.

    Raises
    ------
    InputError
        A volume mesh, no faces, or a NaN or infinite coordinate.
    """
    from p3d_cli.errors import InputError

    where = "<stdin>" if source == "-" else source
    if mesh.tetrahedra is not None:
        raise InputError(where, "is a volume (tetrahedral) mesh; p3d check inspects triangle surfaces",
                         "export the boundary surface")
    triangles = mesh.triangles()
    if len(triangles) == 0:
        raise InputError(where, "the mesh has no faces", "export it again with its faces")
    finite = np.isfinite(triangles).reshape(len(triangles), -1).all(axis=1)
    if not finite.all():
        bad = int(np.flatnonzero(~finite)[0])
        raise InputError(where, f"face {bad} has a NaN or infinite coordinate", "repair or re-export the mesh")
    report = topology(triangles)
    required = tuple(required)
    failed = [name for name in required if not passes(report, name)]
    if min_volume is not None and not report.volume >= min_volume:
        failed.append("min-volume")
    if max_faces is not None and report.faces > max_faces:
        failed.append("max-faces")
    return CheckResult(source, mesh.format, report, required, tuple(failed))
