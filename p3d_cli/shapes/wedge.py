"""Wedge: the half-cube x + y ≤ 0 of [-1, 1]³, scaled (docs/method.md, "Wedge and corner vertices").

Physics3D's built-in wedge constants are wrong (docs/method.md, "Physics3D's wedge and corner
constants"); these are derived from the
geometry below and checked in exact rational arithmetic by ``tests/shapes/test_wedge.py``.

Derivation. Every cross-section z = const is the triangle T with corners (-1,-1), (1,-1),
(-1,1): area 2, centroid (-1/3, -1/3). For a triangle of area A and corners vᵢ,
``∫ v vᵀ dA = A/12 (Σ vᵢvᵢᵀ + s sᵀ)`` with ``s = Σ vᵢ``; here Σxᵢ² = 3, s_x = -1 gives
∫x² dA = 2/12·(3 + 1) = 2/3, and Σxᵢyᵢ = -1, s_x s_y = 1 gives ∫xy dA = 0. Extruding over
z ∈ [-1, 1] (length 2, ∫z² dz = 2/3):

- V = 2·2 = 4, c = (-1/3, -1/3, 0)
- ∫x² dV = ∫y² dV = 4/3, ∫xy dV = 0, ∫z² dV = 2·2/3 = 4/3, ∫xz dV = ∫yz dV = 0
- central: Cxx = 4/3 - V·(1/3)² = 8/9, Cxy = 0 - V·(1/3)(1/3) = -4/9, Czz = 4/3.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as F

import numpy as np

from p3d_cli.shapes import polyhedron

#: The six corners (docs/method.md, "Wedge and corner vertices").
VERTICES = ((-1, -1, -1), (-1, -1, 1), (1, -1, 1), (1, -1, -1), (-1, 1, -1), (-1, 1, 1))
#: Faces counter-clockwise seen from outside: y = -1, x = -1, the slope x + y = 0, z = -1, z = +1.
FACES = ((0, 3, 2, 1), (0, 1, 5, 4), (3, 4, 5, 2), (0, 4, 3), (1, 2, 5))

VOLUME = F(4)
CENTER = (F(-1, 3), F(-1, 3), F(0))
CENTRAL = ((F(8, 9), F(-4, 9), F(0)), (F(-4, 9), F(8, 9), F(0)), (F(0), F(0), F(4, 3)))


@dataclass(frozen=True)
class Wedge(polyhedron.ScaledPolyhedron):
    """The wedge {(x, y, z) in the box of half-extents s : x/sx + y/sy ≤ 0}."""

    name = "wedge"
    form = "wedge or wedge:SX,SY,SZ"
    mirror_symmetric = False
    VERTICES, FACES, VOLUME, CENTER, CENTRAL = VERTICES, FACES, VOLUME, CENTER, CENTRAL

    def inside(self, points) -> np.ndarray:
        """Boolean mask over points in the shape's own frame (closed set)."""
        p = polyhedron.as_points(points)
        in_box = (np.abs(p[:, 0]) <= self.sx) & (np.abs(p[:, 1]) <= self.sy) & (np.abs(p[:, 2]) <= self.sz)
        # x/sx + y/sy ≤ 0, multiplied through by sx·sy > 0 to avoid dividing.
        return in_box & (p[:, 0] * self.sy + p[:, 1] * self.sx <= 0)
