"""The canonical cylinder ``x² + y² ≤ 1, |z| ≤ 1``, shared by the cylinder and the elliptic
cylinder: closed-form constants and an inscribed prism.
"""

from __future__ import annotations

from fractions import Fraction as F

import numpy as np

from p3d_cli.shapes.polyhedron import check_segments

#: Canonical constants, as rational multiples of π.
VOLUME_PER_PI = F(2)
CENTER = (F(0), F(0), F(0))
CENTRAL_PER_PI = ((F(1, 2), F(0), F(0)), (F(0), F(1, 2), F(0)), (F(0), F(0), F(2, 3)))


def unit_cylinder_triangles(n: int) -> np.ndarray:
    """The regular ``n``-gon prism inscribed in the canonical cylinder.

    Its volume is ``n sin(2π/n)`` against ``2π``: relative error ``(2π/n)²/6 + O(n⁻⁴)``.

    Returns
    -------
    (4 n, 3, 3) float64
        Sides as two triangles per segment, caps fanned from their centres; counter-clockwise
        seen from outside.
    """
    n = check_segments(n, lambda k: 4 * k)
    phi = 2 * np.pi * np.arange(n) / n
    ring = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    bottom = np.hstack([ring, np.full((n, 1), -1.0)])
    top = np.hstack([ring, np.full((n, 1), 1.0)])
    j, jn = np.arange(n), (np.arange(n) + 1) % n
    cb = np.broadcast_to([0.0, 0.0, -1.0], (n, 3))
    ct = np.broadcast_to([0.0, 0.0, 1.0], (n, 3))
    sides_a = np.stack([bottom[j], bottom[jn], top[jn]], axis=1)
    sides_b = np.stack([bottom[j], top[jn], top[j]], axis=1)
    caps_top = np.stack([ct, top[j], top[jn]], axis=1)
    caps_bottom = np.stack([cb, bottom[jn], bottom[j]], axis=1)
    return np.concatenate([sides_a, sides_b, caps_top, caps_bottom])
