"""The unit ball, shared by the sphere and the ellipsoid: closed-form constants and an inscribed
polyhedron.

``V = 4π/3``, centre 0, and by symmetry ``∫x² dV = (1/3) ∫|r|² dV = (1/3) ∫₀¹ 4π r⁴ dr = 4π/15``
(likewise y, z), ``∫xy dV = 0``.
"""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np

from p3d_cli.shapes.polyhedron import check_segments

#: Canonical constants, as rational multiples of π.
VOLUME_PER_PI = F(4, 3)
CENTER = (F(0), F(0), F(0))
CENTRAL_PER_PI = ((F(4, 15), F(0), F(0)), (F(0), F(4, 15), F(0)), (F(0), F(0), F(4, 15)))


def unit_sphere_triangles(n: int) -> np.ndarray:
    """A latitude-longitude polyhedron inscribed in the unit sphere.

    ``n`` segments around the z axis and ``max(2, n // 2)`` stacks from pole to pole, so
    every edge is about ``2π/n`` long; all vertices lie on the sphere and the volume error
    falls as ``O(1/n²)``.

    Returns
    -------
    (2 n (stacks - 1), 3, 3) float64
        Counter-clockwise seen from outside.
    """
    n = check_segments(n, lambda k: 2 * k * (max(2, k // 2) - 1))
    stacks = max(2, n // 2)
    theta = np.pi * np.arange(stacks + 1) / stacks
    phi = 2 * np.pi * np.arange(n) / n
    # Ring k is the circle at polar angle theta[k]; rings 0 and `stacks` are the poles
    # (n copies of one point, which makes the cap quads degenerate; those are dropped).
    rings = np.stack([np.outer(np.sin(theta), np.cos(phi)),
                      np.outer(np.sin(theta), np.sin(phi)),
                      np.repeat(np.cos(theta)[:, None], n, axis=1)], axis=-1)
    rings[0] = (0.0, 0.0, 1.0)
    rings[-1] = (0.0, 0.0, -1.0)
    j = np.arange(n)
    jn = (j + 1) % n
    tris = []
    for k in range(stacks):
        upper, lower = rings[k], rings[k + 1]
        # Quad (u_j, l_j, l_j+1, u_j+1) runs down then east: its normal points outward.
        if k != stacks - 1:
            tris.append(np.stack([upper[j], lower[j], lower[jn]], axis=1))
        if k != 0:
            tris.append(np.stack([upper[j], lower[jn], upper[jn]], axis=1))
    return np.concatenate(tris)
