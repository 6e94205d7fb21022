"""Vertices within a tolerance taken as one: ``p3d check --weld TOL``, never the default.

p3d matches vertices by exact coordinates. A file whose seams differ in the last digits (a
mesh exported through float32, or stitched by hand) is then open, and ``--weld`` says how near
it is to closed: vertices closer than ``TOL`` (Euclidean distance, in the file's units) are
merged, and the checks run on the result. Merging is transitive (a chain of near vertices
becomes one), so the report gives the number of vertices merged away and the largest distance
between a merged vertex and the one it became, which may exceed ``TOL`` along a chain.

Near pairs are found on a grid of cells of size ``TOL``: two points within ``TOL`` lie in the
same or adjacent cells, so each cell is compared with itself and its 13 neighbours ahead of it.
Each group takes the coordinates of one of its vertices, so the welded mesh holds only
coordinates the file holds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.mesh.shells import roots

#: Cell offsets ahead of a cell (with the cell itself, every neighbouring pair once).
_AHEAD = [(dx, dy, dz) for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1) if (dx, dy, dz) > (0, 0, 0)]


@dataclass(frozen=True)
class Weld:
    """What ``--weld`` merged.

    Attributes
    ----------
    tolerance : float
    vertices : int
        Distinct vertices merged into another (the mesh has this many fewer).
    largest_distance : float
        The largest distance between a merged vertex and the vertex it became.
    """

    tolerance: float
    vertices: int
    largest_distance: float

    def to_dict(self) -> dict:
        return {"tolerance": self.tolerance, "vertices": self.vertices, "largest_distance": self.largest_distance}


def check_tolerance(tolerance: float) -> float:
    """``tolerance`` as a positive finite float (UsageError naming ``weld`` otherwise)."""
    value = float(tolerance)
    if not (np.isfinite(value) and value > 0):
        raise UsageError("weld", f"tolerance {tolerance!r} is not a positive number",
                         "give the largest distance between vertices to merge, in the file's units")
    return value


def weld_points(points: np.ndarray, tolerance: float) -> tuple[np.ndarray, Weld]:
    """For each of ``points`` ``(m, 3)``, the index of the point it is merged into.

    Returns
    -------
    target : (m,) int64
        The smallest index of the point's group.
    Weld
    """
    points = np.asarray(points, dtype=np.float64)
    m = len(points)
    tolerance = check_tolerance(tolerance)
    if m < 2:
        return np.arange(m, dtype=np.int64), Weld(tolerance, 0, 0.0)
    cell = np.floor((points - points.min(axis=0)) / tolerance).astype(np.int64)
    span = cell.max(axis=0) + 3
    key = (cell[:, 0] * span[1] + cell[:, 1]) * span[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    starts = np.flatnonzero(np.r_[True, sorted_key[1:] != sorted_key[:-1]])
    ends = np.r_[starts[1:], sorted_key.size]
    cells = sorted_key[starts]
    a_list, b_list = [], []
    for offset in [(0, 0, 0)] + _AHEAD:
        shift = (offset[0] * span[1] + offset[1]) * span[2] + offset[2]
        at = np.searchsorted(cells, cells + shift)
        at = np.minimum(at, cells.size - 1)
        c = np.flatnonzero(cells[at] == cells + shift)
        d = at[c]
        size_c, size_d = ends[c] - starts[c], ends[d] - starts[d]
        count = size_c * size_d
        pair = np.repeat(np.arange(c.size), count)
        step = np.arange(pair.size) - np.repeat(np.cumsum(count) - count, count)
        i = order[starts[c][pair] + step // size_d[pair]]
        j = order[starts[d][pair] + step % size_d[pair]]
        keep = i < j if shift == 0 else np.ones(i.size, dtype=bool)
        i, j = i[keep], j[keep]
        near = ((points[i] - points[j]) ** 2).sum(axis=1) <= tolerance * tolerance
        a_list.append(i[near])
        b_list.append(j[near])
    a = np.concatenate(a_list) if a_list else np.zeros(0, dtype=np.int64)
    b = np.concatenate(b_list) if b_list else np.zeros(0, dtype=np.int64)
    target = roots(m, a, b)
    moved = np.flatnonzero(target != np.arange(m))
    largest = float(np.sqrt(((points[moved] - points[target[moved]]) ** 2).sum(axis=1)).max()) if moved.size else 0.0
    return target, Weld(tolerance, int(moved.size), largest)


def weld_triangles(triangles: np.ndarray, tolerance: float) -> tuple[np.ndarray, Weld]:
    """``triangles`` ``(n, 3, 3)`` with every corner moved to the vertex it is merged into."""
    from p3d_cli.mesh.topology import corner_vertex_ids

    ids, points = corner_vertex_ids(triangles)
    target, report = weld_points(points, tolerance)
    return points[target][ids].astype(np.float64), report
