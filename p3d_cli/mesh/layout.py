"""What the topology pass knows about a mesh that later passes over it reuse (no second sort)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.edges import Edges
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
    edges : Edges or None
        The sides grouped by edge (``p3d_cli.mesh.edges``; ``forward`` not kept: a side's
        direction is ``ids[side] < ids[next side]``). When ``p3d_cli.mesh.paired``'s path found
        the mesh, which groups no edges: None when every edge is used once each way, and when
        some once (boundary edges) the boundary sides alone (``edges.lone_sides``), or None if
        the caller asked for no edges (``topology_and_layout(edges=False)``). For ``p3d
        repair``, which asks for them and reads only the problem groups.
    duplicates : (k, 2) int64 or None
        ``(first face, later duplicate)`` rows (``faces.duplicate_faces``), when ``edges`` is.
    """

    ids: np.ndarray
    vertex_count: int
    shells: Components
    zero_area: np.ndarray
    crowded_edges: np.ndarray
    open_shells: np.ndarray
    edges: Edges | None = None
    duplicates: np.ndarray | None = None

    @property
    def faces(self) -> np.ndarray:
        """Vertex ids ``(n, 3)`` of every face."""
        return self.ids.reshape(-1, 3)


def vertex_points(blocks, layout: Layout) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of the mesh, renumbered in the order the file uses them.

    The topology numbers vertices in the order of their hashes, at random in space; numbered
    by the place of one of their corners, the vertices of faces near each other in the file
    are near each other in memory, which the passes gathering them by face (the
    self-intersection test) read several times faster. ``layout.ids`` are renumbered in
    place (the topology is done with them; a second copy would cost as much memory again).

    Returns
    -------
    points : (m, 3) float64
        The coordinates of every vertex used (-0.0 read as 0.0), from one more pass over the
        triangles; ``layout.faces`` index them.
    rank : (vertex_count,) int
        The new number of each old vertex id (for ids kept elsewhere, such as edges').
    """
    ids = layout.ids
    # Some corner of every vertex (whichever assignment numpy makes last: any one will do),
    # and the vertices ranked by it. Ids no corner uses rank last.
    corner = np.full(layout.vertex_count, ids.size, dtype=np.int64)
    corner[ids] = np.arange(ids.size)
    order = np.argsort(corner, kind="stable")
    used = int(np.count_nonzero(corner < ids.size))
    rank = np.empty(layout.vertex_count, dtype=ids.dtype)
    rank[order] = np.arange(layout.vertex_count, dtype=ids.dtype)
    del corner, order
    for start in range(0, ids.size, 1 << 18):
        np.take(rank, ids[start:start + (1 << 18)], out=ids[start:start + (1 << 18)])
    points = np.zeros((used, 3), dtype=np.float64)
    done = 0
    for block in blocks():
        corners = np.asarray(block, dtype=np.float64).reshape(-1, 3)
        points[ids[done:done + len(corners)]] = corners
        done += len(corners)
    np.add(points, 0.0, out=points)
    return points, rank
