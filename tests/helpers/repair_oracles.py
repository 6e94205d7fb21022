"""Slow, obviously right stand-ins for the exact tests ``p3d_cli.repairs.solidity`` reaches,
for testing the repair steps on their own: a brute-force weld, and the nesting of axis-aligned
boxes (for box-shaped shells, box containment is exactly shell containment)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Welded:
    vertices: int
    largest_distance: float


def brute_weld(points: np.ndarray, tolerance: float):
    """Every pair compared: ``(target, Welded)``, each point merged into the smallest index of
    its group (transitively)."""
    points = np.asarray(points, dtype=np.float64)
    m = len(points)
    parent = list(range(m))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i in range(m):
        for j in range(i + 1, m):
            if float(np.sum((points[i] - points[j]) ** 2)) <= tolerance * tolerance:
                a, b = root(i), root(j)
                parent[max(a, b)] = min(a, b)
    target = np.array([root(i) for i in range(m)], dtype=np.int64)
    moved = np.flatnonzero(target != np.arange(m))
    largest = float(np.sqrt(((points[moved] - points[target[moved]]) ** 2).sum(axis=1)).max()) if moved.size else 0.0
    return target, Welded(int(moved.size), largest)


def box_nesting(points, faces, labels, count, closed) -> dict[int, int]:
    """Depth of every closed shell: how many other closed shells' boxes hold its box."""
    points = np.asarray(points, dtype=np.float64)
    boxes = {}
    for s in np.asarray(closed).tolist():
        corners = points[np.asarray(faces)[np.asarray(labels) == s].ravel()]
        boxes[s] = (corners.min(axis=0), corners.max(axis=0))
    return {s: sum(1 for t in boxes if t != s and (boxes[t][0] <= boxes[s][0]).all()
                   and (boxes[s][1] <= boxes[t][1]).all()) for s in boxes}
