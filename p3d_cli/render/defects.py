"""Where a mesh's defects are: every problem edge and face, as geometry to draw.

``p3d check`` counts the problems and lists a few locations; a picture needs all of them. The
definitions are check's own (``p3d_cli.mesh.topology``): vertices are matched by exact
coordinates (``corner_vertex_ids``), an edge is an unordered pair of distinct vertices used by
some face side, and

- a boundary edge is used by exactly one face;
- a non-manifold edge by more than two;
- a misoriented edge by exactly two faces that traverse it in the same direction;
- a degenerate face has exactly zero area (``p3d_cli.mesh.faces.zero_area_faces``, exact).

The tests compare these counts with ``p3d check``'s on the same meshes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class DefectGeometry:
    """Every problem of a triangle soup, as coordinates.

    Attributes
    ----------
    boundary, nonmanifold, misoriented : (k, 2, 3) float64
        The end points of each problem edge.
    degenerate : (m,) int64
        Indices of the zero-area faces.
    degenerate_points : (m, 3) float64
        Their centroids (where to mark them: they cover no pixel).
    """

    boundary: np.ndarray
    nonmanifold: np.ndarray
    misoriented: np.ndarray
    degenerate: np.ndarray
    degenerate_points: np.ndarray

    @property
    def any(self) -> bool:
        return bool(len(self.boundary) or len(self.nonmanifold) or len(self.misoriented) or len(self.degenerate))


def defect_geometry(triangles: np.ndarray) -> DefectGeometry:
    """The problem edges and faces of ``triangles``.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64
        Finite corner coordinates.

    Returns
    -------
    DefectGeometry
    """
    from p3d_cli.mesh.faces import zero_area_faces
    from p3d_cli.mesh.topology import corner_vertex_ids

    triangles = np.asarray(triangles)
    n = len(triangles)
    empty = np.zeros((0, 2, 3))
    if n == 0:
        return DefectGeometry(empty, empty, empty, np.zeros(0, dtype=np.int64), np.zeros((0, 3)))
    ids, points = corner_vertex_ids(triangles)
    start = ids.reshape(-1)
    end = np.roll(ids, -1, axis=1).reshape(-1)          # side k runs from corner k to corner k + 1
    real = start != end                                  # a side whose ends coincide bounds nothing
    start, end = start[real], end[real]
    lo, hi = np.minimum(start, end), np.maximum(start, end)
    forward = start < end
    key = lo * np.int64(len(points)) + hi
    order = np.argsort(key, kind="stable")
    key, forward, lo, hi = key[order], forward[order], lo[order], hi[order]
    first = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    counts = np.diff(np.r_[first, key.size])
    ahead = np.add.reduceat(forward.astype(np.int64), first) if first.size else np.zeros(0, dtype=np.int64)
    groups = {
        "boundary": first[counts == 1],
        "nonmanifold": first[counts > 2],
        # Two uses in the same direction: both forward or both backward.
        "misoriented": first[(counts == 2) & (ahead != 1)],
    }
    edges = {name: np.stack([points[lo[g]], points[hi[g]]], axis=1) if g.size else empty
             for name, g in groups.items()}
    cols = np.ascontiguousarray(np.transpose(triangles, (1, 2, 0)), dtype=np.float64)
    zero = zero_area_faces(cols)
    centroids = triangles[zero].astype(np.float64).mean(axis=1) if zero.size else np.zeros((0, 3))
    return DefectGeometry(edges["boundary"], edges["nonmanifold"], edges["misoriented"], zero, centroids)
