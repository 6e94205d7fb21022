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
    another face. Only the faces whose boxes meet the new faces' box take part."""
    new = np.asarray(new, dtype=np.int64)
    if new.size == 0:
        return new
    from p3d_cli.mesh.intersections import self_intersections

    points = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces)
    corners = points[faces[new]]
    lo, hi = corners.min(axis=(0, 1)), corners.max(axis=(0, 1))
    # A face's box misses the new faces' box when, along some axis, all three of its corners
    # lie beyond it on one side: decided per vertex once, then per face on booleans.
    below, above = points < lo, points > hi
    away = np.zeros(len(faces), dtype=bool)
    for axis in range(3):
        for side in (below[:, axis], above[:, axis]):
            on = side[faces]
            away |= on[:, 0] & on[:, 1] & on[:, 2]
    chosen = np.flatnonzero(~away)
    found = self_intersections(points, faces[chosen])
    hit = np.unique(chosen[found.pairs].ravel()) if len(found.pairs) else np.zeros(0, dtype=np.int64)
    return np.intersect1d(hit, new)
