"""What the topology pass knows about a mesh that later passes over it reuse (no second sort)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.shells import Components


@dataclass(frozen=True)
class Layout:
    """Vertex ids, shells and problem edges of a triangle soup, as ``topology`` found them.

    Attributes
    ----------
    ids : (3n,) int
        Vertex id of corner ``3 f + k``: equal exactly when the coordinates are (``-0.0 ==
        0.0``); ids are below ``vertex_count`` (not necessarily all used).
    vertex_count : int
    shells : Components
        The shell of every face (faces joined across shared edges).
    zero_area : (z,) int64
        Faces of exactly zero area.
    crowded_edges : (e, 2) int64
        Vertex ids of the edges used by more than two faces.
    open_shells : (s,) int64
        Shells with a boundary, non-manifold or misoriented edge (the others are closed).
    """

    ids: np.ndarray
    vertex_count: int
    shells: Components
    zero_area: np.ndarray
    crowded_edges: np.ndarray
    open_shells: np.ndarray

    @property
    def faces(self) -> np.ndarray:
        """Vertex ids ``(n, 3)`` of every face."""
        return self.ids.reshape(-1, 3)


def vertex_points(blocks, layout: Layout) -> np.ndarray:
    """The coordinates ``(vertex_count, 3)`` float64 of every vertex id, from one more pass
    over the triangles (-0.0 read as 0.0; ids no corner uses stay 0)."""
    points = np.zeros((layout.vertex_count, 3), dtype=np.float64)
    done = 0
    for block in blocks():
        corners = np.asarray(block, dtype=np.float64).reshape(-1, 3)
        points[layout.ids[done:done + len(corners)]] = corners
        done += len(corners)
    return points + 0.0
