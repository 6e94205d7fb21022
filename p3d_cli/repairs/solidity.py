"""What repair takes from ``p3d check``'s exact solidity tests, in the steps' vocabulary.

- ``weld_points``: ``p3d check --weld``'s grouping of near vertices (``p3d_cli.mesh.weld``);
- ``nesting_depths``: how many closed shells lie around each closed shell, by exact winding
  numbers (``p3d_cli.mesh.nesting``), for the ``outward`` step (a shell inside an odd number of
  others is a cavity);
- ``new_face_crossings``: the new faces of filled holes whose interiors cross or overlap
  another face (``p3d_cli.mesh.intersections``, on the faces near the holes only): a filled
  hole must add no self-intersection.

The modules are imported where they are used: a repair that needs none of them does not load
the self-intersection machinery.
"""

from __future__ import annotations

import numpy as np


def weld_points(points: np.ndarray, tolerance: float):
    """``(target, weld)``: for every point ``(m, 3)`` the smallest index of the points it is
    merged with (transitively, closer than ``tolerance``), and what was merged."""
    from p3d_cli.mesh.weld import weld_points as groups

    return groups(points, tolerance)


def nesting_depths(points: np.ndarray, faces: np.ndarray, labels: np.ndarray, count: int,
                   closed: np.ndarray) -> dict[int, int]:
    """How many closed shells lie around each closed shell, decided exactly.

    Parameters
    ----------
    points : (m, 3)
        Coordinates by vertex id (one id per distinct point).
    faces : (k, 3) int
    labels : (k,) int
        Shell of every face, ``0..count-1``.
    closed : (s,) int
        The closed shells (the others take no part).

    Returns
    -------
    dict
        ``{shell: depth}`` for every closed shell (0: in no other).
    """
    closed = np.asarray(closed, dtype=np.int64)
    if closed.size <= 1:
        return {int(s): 0 for s in closed}
    from p3d_cli.mesh.layout import Layout
    from p3d_cli.mesh.nesting import shell_nesting
    from p3d_cli.mesh.shells import Components

    faces = np.asarray(faces)
    others = np.setdiff1d(np.arange(count), closed)
    layout = Layout(faces.ravel(), len(points), Components(np.asarray(labels), count), np.zeros(0, dtype=np.int64),
                    np.zeros((0, 2), dtype=np.int64), others)
    found = shell_nesting(np.asarray(points, dtype=np.float64), faces, layout, np.zeros((0, 2), dtype=np.int64))
    depth: dict[int, int] = {}
    for shell in closed.tolist():
        d, outer = 0, found.parent.get(shell)
        while outer is not None:
            d += 1
            outer = found.parent.get(outer)
        depth[shell] = d
    return depth


def new_face_crossings(points: np.ndarray, faces: np.ndarray, new: np.ndarray) -> np.ndarray:
    """The faces among ``new`` (indices into ``faces``) whose interiors cross or overlap
    another face. Only the faces whose boxes may meet a new face's box take part
    (``near_new_faces``)."""
    new = np.asarray(new, dtype=np.int64)
    if new.size == 0:
        return new
    from p3d_cli.mesh.intersections import self_intersections

    points = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces)
    chosen = near_new_faces(points, faces, new)
    found = self_intersections(points, faces[chosen])
    hit = np.unique(chosen[found.pairs].ravel()) if len(found.pairs) else np.zeros(0, dtype=np.int64)
    return np.intersect1d(hit, new)


#: Odd 64-bit multipliers mixing a grid cell's three indices into one key.
_MIX = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9], dtype=np.uint64)


def near_new_faces(points: np.ndarray, faces: np.ndarray, new: np.ndarray) -> np.ndarray:
    """The faces (sorted ids, ``new`` among them) whose boxes may meet the box of a face in
    ``new``: a superset of those that do, never missing one.

    A grid of cells as large as the largest new face's box: a new face's box covers at most
    two cells along each axis, and two boxes that meet share a cell (the cell of a point in
    both). An old face is kept when one of its cells holds a new face (cell keys are hashed:
    a collision keeps a face too many, never one too few), or when it is larger than a cell
    (kept without looking). Many small holes spread over a large mesh thus test only the faces
    around each hole, where one box around all of them would take in the whole mesh.
    """
    corners = [points[faces[:, k]] for k in range(3)]
    lo = np.minimum(np.minimum(corners[0], corners[1]), corners[2])
    hi = np.maximum(np.maximum(corners[0], corners[1]), corners[2])
    del corners
    size = float((hi[new] - lo[new]).max())
    if not np.isfinite(size) or size <= 0.0:
        size = 1.0
    origin = lo[new].min(axis=0)
    with np.errstate(over="ignore", invalid="ignore"):
        first = np.floor((lo - origin) / size)
        last = np.floor((hi - origin) / size)
    # Cells far beyond int64 (a face 1e300 away) are far from every new face: clipped, they
    # still compare as different cells from the new faces' (which lie near the origin).
    first = np.clip(np.nan_to_num(first, nan=-2.0**62), -2.0**62, 2.0**62).astype(np.int64)
    last = np.clip(np.nan_to_num(last, nan=2.0**62), -2.0**62, 2.0**62).astype(np.int64)
    occupied = np.unique(np.concatenate([_keys(first[new], last[new], corner) for corner in range(8)]))
    small = ((last - first) <= 1).all(axis=1)
    near = ~small
    for corner in range(8):
        keys = _keys(first, last, corner)
        at = np.searchsorted(occupied, keys)
        at[at == len(occupied)] = 0
        near |= small & (occupied[at] == keys)
    near[new] = True
    return np.flatnonzero(near)


def _keys(first: np.ndarray, last: np.ndarray, corner: int) -> np.ndarray:
    """The hashed key of each box's cell at ``corner`` (bit k: the last cell along axis k)."""
    cell = np.where([(corner >> k) & 1 for k in range(3)], last, first).astype(np.uint64)
    with np.errstate(over="ignore"):
        mixed = cell * _MIX
    return mixed[:, 0] ^ (mixed[:, 1] >> np.uint64(1)) ^ (mixed[:, 2] << np.uint64(1))
