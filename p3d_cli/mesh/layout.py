"""What the topology pass knows about a mesh that later passes over it reuse (no second sort)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.edges import Edges
from p3d_cli.mesh.shells import Components


@dataclass(frozen=True)
class Layout:
    """Vertex ids, shells and edges of a triangle soup, as ``topology`` found them.

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
    edges : Edges or None
        The sides grouped by edge (``p3d_cli.mesh.edges``; ``forward`` not kept: a side's
        direction is ``ids[side] < ids[next side]``), or None when every edge is used once
        each way (``p3d_cli.mesh.paired``'s path, which groups no edges).
    duplicates : (k, 2) int64 or None
        ``(first face, later duplicate)`` rows (``faces.duplicate_faces``), when ``edges`` is.
    """

    ids: np.ndarray
    vertex_count: int
    shells: Components
    zero_area: np.ndarray
    edges: Edges | None = None
    duplicates: np.ndarray | None = None

    @property
    def faces(self) -> np.ndarray:
        """Vertex ids ``(n, 3)`` of every face."""
        return self.ids.reshape(-1, 3)
