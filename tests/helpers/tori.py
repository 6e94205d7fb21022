"""Grid tori for tests: closed, consistently wound outward meshes of any size, anywhere."""

from __future__ import annotations

import numpy as np


def grid_torus(u: int, v: int, scale: float = 1.0, at=(0.0, 0.0, 0.0)) -> np.ndarray:
    """Triangles ``(2 u v, 3, 3)`` float64 of a torus (ring radius 3, tube radius 1, times
    ``scale``, centred at ``at``), wound outward; ``benchmarks/torus.py`` writes the same grid."""
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = 3.0 + np.cos(phi)
    points = np.stack([ring * np.cos(theta), ring * np.sin(theta), np.sin(phi)], axis=-1).reshape(-1, 3)
    a, b = (i * v + j).ravel(), (((i + 1) % u) * v + j).ravel()
    c, d = (((i + 1) % u) * v + (j + 1) % v).ravel(), (i * v + (j + 1) % v).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return (points * scale + np.asarray(at, dtype=np.float64))[faces]
