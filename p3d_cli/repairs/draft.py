"""A mesh under repair: the input's triangles, and its faces as they are after each step.

Every face remembers where it came from, so that the output can write each face the input had
exactly as the input stored it (bit for bit, the sign of a zero included), and so that the
report can name each change by the input's own face numbers:

- ``origin``: the input face it is (0-based, file order), or -1 for a face a step added;
- ``flipped``: its corners 1 and 2 swapped (the same three corners, the other way round);
- ``moved``: a corner moved by the weld step to the vertex it was merged into.

The faces are vertex ids (``points`` holds each vertex's coordinates, in the input's own
dtype); ids are the exact vertex ids of ``p3d check`` (``p3d_cli.mesh.topology``), so two
corners share an id exactly when their coordinates are equal.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.edges import Edges, group_edges, next_corner
from p3d_cli.mesh.vertices import Corners


@dataclass(frozen=True)
class Draft:
    """The faces of a mesh under repair (see the module docstring).

    Attributes
    ----------
    triangles : (n, 3, 3) float32 or float64
        The input's triangles, as stored.
    points : (m, 3) float32 or float64
        Coordinates of every vertex id.
    faces : (k, 3) int64
        Vertex ids of the current faces.
    origin : (k,) int64
    flipped : (k,) bool
    moved : (k,) bool
    """

    triangles: np.ndarray
    points: np.ndarray
    faces: np.ndarray
    origin: np.ndarray
    flipped: np.ndarray
    moved: np.ndarray

    @classmethod
    def of(cls, triangles: np.ndarray, ids: np.ndarray, points: np.ndarray) -> "Draft":
        """The input as a draft: ``ids`` ``(n, 3)`` exact vertex ids, ``points`` by id."""
        n = len(triangles)
        return cls(triangles, points, np.asarray(ids, dtype=np.int64).reshape(n, 3),
                   np.arange(n, dtype=np.int64), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool))

    def keep(self, mask: np.ndarray) -> "Draft":
        """Only the faces where ``mask`` is True."""
        return dataclasses.replace(self, faces=self.faces[mask], origin=self.origin[mask],
                                   flipped=self.flipped[mask], moved=self.moved[mask])

    def flip(self, mask: np.ndarray) -> "Draft":
        """The faces where ``mask`` is True turned round (corners 1 and 2 swapped)."""
        faces = self.faces.copy()
        faces[mask] = faces[mask][:, [0, 2, 1]]
        return dataclasses.replace(self, faces=faces, flipped=self.flipped ^ mask)

    def add(self, faces: np.ndarray) -> "Draft":
        """New faces ``(j, 3)`` (vertex ids) after the others."""
        j = len(faces)
        return dataclasses.replace(
            self, faces=np.concatenate([self.faces, np.asarray(faces, dtype=np.int64).reshape(j, 3)]),
            origin=np.concatenate([self.origin, np.full(j, -1, dtype=np.int64)]),
            flipped=np.concatenate([self.flipped, np.zeros(j, dtype=bool)]),
            moved=np.concatenate([self.moved, np.zeros(j, dtype=bool)]))

    def replaced(self, rows: np.ndarray, faces: np.ndarray) -> "Draft":
        """Faces ``rows`` given new corners ``faces`` ``(r, 3)`` (a face split: the same input face,
        made smaller); they are marked ``moved``, so their coordinates come from ``points``."""
        rows = np.asarray(rows, dtype=np.int64)
        new = self.faces.copy()
        new[rows] = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        moved = self.moved.copy()
        moved[rows] = True
        return dataclasses.replace(self, faces=new, moved=moved)

    def renamed(self, target: np.ndarray, points: np.ndarray | None = None) -> "Draft":
        """Every vertex id ``v`` replaced by ``target[v]`` (a weld); faces whose corners changed
        are marked ``moved``."""
        faces = target[self.faces]
        moved = self.moved | (faces != self.faces).any(axis=1)
        return dataclasses.replace(self, faces=faces, moved=moved,
                                   points=self.points if points is None else points)

    @property
    def changed(self) -> bool:
        """Whether the faces differ from the input's."""
        n = len(self.triangles)
        return bool(len(self.origin) != n or self.flipped.any() or self.moved.any()
                    or not np.array_equal(self.origin, np.arange(n)))

    def output_triangles(self) -> np.ndarray:
        """The faces as triangles ``(k, 3, 3)`` in the input's dtype: each input face not moved
        exactly as the input stored it (flipped ones with corners 1 and 2 swapped), the others
        from their vertices' coordinates."""
        out = np.empty((len(self.faces), 3, 3), dtype=self.triangles.dtype)
        kept = (self.origin >= 0) & ~self.moved
        rows = np.flatnonzero(kept)
        source = self.origin[rows]
        if rows.size and rows[-1] == rows.size - 1 and source[-1] - source[0] == rows.size - 1:
            out[:rows.size] = self.triangles[source[0]:source[-1] + 1]     # one run: a copy, no gather
        else:
            out[rows] = self.triangles[source]
        turned = np.flatnonzero(kept & self.flipped)
        if turned.size:
            out[turned] = out[turned][:, [0, 2, 1]]
        built = np.flatnonzero(~kept)
        if built.size:
            out[built] = self.points[self.faces[built]]
        return out

    def indexed(self) -> tuple[np.ndarray, np.ndarray]:
        """``(vertices, faces)``: the vertices the faces use, numbered in order of first use
        (file order), in the input's dtype."""
        flat = self.faces.ravel()
        first = np.full(len(self.points), flat.size, dtype=np.int64)
        np.minimum.at(first, flat, np.arange(flat.size))
        used = np.flatnonzero(first < flat.size)
        used = used[np.argsort(first[used], kind="stable")]
        number = np.empty(len(self.points), dtype=np.int64)
        number[used] = np.arange(used.size)
        return self.points[used], number[self.faces]


@dataclass(frozen=True)
class Grouping:
    """A draft's edges grouped once (``draft_edges``), with the faces and the windings they were
    grouped on (the steps after it only flip or add faces, so its face numbers stay valid).

    Attributes
    ----------
    edges : Edges
    faces : (k, 3) int64
    flipped : (k,) bool
        ``Draft.flipped`` when grouped: a face flipped since has its sides the other way round.
    """

    edges: Edges
    faces: np.ndarray
    flipped: np.ndarray


def grouping(draft: Draft) -> Grouping:
    """The edges of ``draft``'s faces (``draft_edges``)."""
    return Grouping(draft_edges(draft.faces), draft.faces, draft.flipped.copy())


def with_directions(edges: Edges, ids: np.ndarray) -> Edges:
    """``edges`` with ``forward`` (which the topology lets go) from the vertex ids ``(3n,)``:
    side ``3 f + k`` runs forward when its start's id is below its end's.

    Only the orient step reads ``forward``, to tell which two sides of an edge disagree, and
    only when the topology found misoriented edges: without them ``forward`` stays None (its
    two gathers of ``3n`` ids took 1.3 s of the open 1M torus's repair)."""
    if edges.forward is not None or edges.misoriented.size == 0:
        return edges
    side = edges.side.astype(np.int64)
    ids = np.asarray(ids).ravel()
    return dataclasses.replace(edges, forward=ids[side] < ids[next_corner(side)])


def draft_edges(faces: np.ndarray) -> Edges:
    """The edges of ``faces`` ``(k, 3)`` (vertex ids), grouped by ``p3d check``'s own edge code
    (``p3d_cli.mesh.edges.group_edges``): sides ``3 f + j`` (corner ``j`` to ``j + 1`` of face
    ``f``), their directions, and the boundary, non-manifold and misoriented groups.

    Vertex ids are renumbered densely first (faces may have been removed), and the corners
    sorted by vertex as ``p3d_cli.mesh.vertices`` sorts them.
    """
    k = len(faces)
    flat = np.asarray(faces, dtype=np.int64).ravel()
    present = np.zeros(int(flat.max()) + 1 if flat.size else 0, dtype=bool)
    present[flat] = True
    dense = np.cumsum(present) - 1
    small = np.int32 if 3 * k < 2**31 else np.int64
    ids = dense[flat].astype(small)
    m = int(present.sum())
    bits = max(int(3 * k - 1).bit_length(), 1)
    keys = (ids.astype(np.uint64) << np.uint64(bits)) | np.arange(3 * k, dtype=np.uint64)
    keys.sort()
    first = np.zeros(m + 1, dtype=small)
    np.cumsum(np.bincount(ids, minlength=m), out=first[1:])
    corners = Corners(ids=ids, keys=keys, bits=bits, first=first, points=np.zeros((0, 3)), volume=0.0)
    return group_edges(corners)
