"""Closed triangle meshes whose self-intersections are known by construction."""

from __future__ import annotations

import numpy as np

#: The cube's corners by bits (x, y, z) and its six faces, each a quad wound outwards.
_CORNERS = np.array([[(i >> 0) & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
_QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]


def box(lo, hi, diagonals=None, inward: bool = False) -> np.ndarray:
    """The box ``[lo, hi]`` as 12 triangles wound outwards (inwards with ``inward``).

    ``diagonals``: six booleans choosing each face's diagonal (default: all the first one),
    so that two boxes sharing a face can be triangulated alike or differently.
    """
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    points = lo + _CORNERS * (hi - lo)
    faces = []
    for quad, other in zip(_QUADS, diagonals if diagonals is not None else [False] * 6):
        a, b, c, d = quad
        faces += [(a, b, d), (b, c, d)] if other else [(a, b, c), (a, c, d)]
    triangles = points[np.array(faces)]
    return triangles[:, ::-1] if inward else triangles


def octahedron(centre, radius: float) -> np.ndarray:
    """The octahedron with vertices ``centre ± radius`` along each axis, wound outwards."""
    p = np.array([[1, 0, 0], [0, 1, 0], [-1, 0, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], float)
    p = p * radius + np.asarray(centre, dtype=float)
    faces = []
    for k in range(4):
        a, b = k, (k + 1) % 4
        faces += [(a, b, 4), (b, a, 5)]
    return p[np.array(faces)]


def grid(n: int, height=None) -> tuple[np.ndarray, np.ndarray]:
    """A scan-like open height field: ``(n + 1)²`` vertices over ``[0, n]²`` and ``2 n²`` faces
    wound upwards; ``height(x, y)`` gives z (default 0)."""
    i, j = np.meshgrid(np.arange(n + 1), np.arange(n + 1), indexing="ij")
    x, y = i.astype(float), j.astype(float)
    z = np.zeros_like(x) if height is None else height(x, y)
    points = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    v = lambda a, b: a * (n + 1) + b
    faces = []
    for a in range(n):
        for b in range(n):
            faces += [(v(a, b), v(a + 1, b), v(a + 1, b + 1)), (v(a, b), v(a + 1, b + 1), v(a, b + 1))]
    return points, np.array(faces)


def indexed(triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(points, faces)`` of a triangle soup, vertices matched by exact coordinates."""
    points, ids = np.unique(np.asarray(triangles, dtype=float).reshape(-1, 3), axis=0, return_inverse=True)
    return points, ids.reshape(-1, 3)
