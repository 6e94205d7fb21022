"""Pure functions shared by the polyhedral shape classes (box, wedge, corner).

A polyhedral class is a list of canonical vertices in [-1, 1]³ and faces wound
counter-clockwise seen from outside. Its placed bounds are exact by vertex projection
(the design note's eq. 10, generalised from the box's 8 corners to any vertex list): a
linear map sends the convex hull of the vertices to the convex hull of their images, and
a box around a convex hull is attained at vertices.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.results import Bounds


def scaled_vertices(vertices, scale) -> np.ndarray:
    """Canonical vertices ``(k, 3)`` mapped by the diagonal scale: ``(k, 3) float64``."""
    return np.asarray(vertices, dtype=np.float64) * np.asarray(scale, dtype=np.float64)


def projected_bounds(points: np.ndarray, rotation=None, translation=None) -> Bounds:
    """Axis-aligned box of ``R p + t`` over the points.

    Parameters
    ----------
    points : (k, 3) float64
    rotation : (3, 3) array_like, optional
        Default the identity.
    translation : (3,) array_like, optional
        Default zero.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    if rotation is None:
        lo, hi = pts.min(axis=0), pts.max(axis=0)
    else:
        # One contiguous projection per world axis, reduced at once: about 3-5 times faster
        # than ``pts @ R.T`` followed by strided column reductions on an (n, 3) array.
        r = np.asarray(rotation, dtype=np.float64)
        x, y, z = pts[:, 0], pts[:, 1], pts[:, 2]
        lo, hi = np.empty(3), np.empty(3)
        for i in range(3):
            proj = x * r[i, 0]
            proj += y * r[i, 1]
            proj += z * r[i, 2]
            lo[i], hi[i] = proj.min(), proj.max()
    if translation is not None:
        t = np.asarray(translation, dtype=np.float64).reshape(3)
        lo, hi = lo + t, hi + t
    return Bounds(lo, hi)


def face_triangles(vertices: np.ndarray, faces) -> np.ndarray:
    """Triangles ``(n, 3, 3)`` from polygon faces (index lists, fanned from their first corner)."""
    tris = []
    for face in faces:
        for k in range(1, len(face) - 1):
            tris.append((face[0], face[k], face[k + 1]))
    return np.asarray(vertices, dtype=np.float64)[np.asarray(tris)]


def as_points(points) -> np.ndarray:
    """Points as ``(n, 3) float64`` (a single point becomes one row)."""
    return np.asarray(points, dtype=np.float64).reshape(-1, 3)
