"""Corner: the tetrahedron (-1,-1,-1) (-1,-1,1) (-1,1,-1) (1,-1,-1), scaled (docs/method.md,
"Wedge and corner vertices").

Physics3D's built-in corner constants are wrong (integer division; docs/method.md, "Physics3D's
wedge and corner constants"); these are derived from the geometry and checked in exact rational arithmetic by
``tests/shapes/test_corner.py``.

Derivation. A tetrahedron with corners vᵢ has V = |det(v1-v0, v2-v0, v3-v0)|/6, centroid the
mean of the corners and ``∫ v vᵀ dV = V/20 (Σ vᵢvᵢᵀ + s sᵀ)`` with ``s = Σ vᵢ``. Here the
edges from (-1,-1,-1) are 2e_z, 2e_y, 2e_x, so V = 8/6 = 4/3 and c = (-1/2, -1/2, -1/2).
Σxᵢ² = 4, s_x = -2: ∫x² dV = (4/3)/20·(4 + 4) = 8/15; Σxᵢyᵢ = 1 + 1 - 1 - 1 = 0,
s_x s_y = 4: ∫xy dV = (4/3)/20·4 = 4/15. Central: Cxx = 8/15 - (4/3)(1/4) = 1/5,
Cxy = 4/15 - (4/3)(1/4) = -1/15; the other entries follow by the x, y, z symmetry.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as F

import numpy as np

from p3d_cli.shapes import polyhedron

#: The four corners (docs/method.md, "Wedge and corner vertices").
VERTICES = ((-1, -1, -1), (-1, -1, 1), (-1, 1, -1), (1, -1, -1))
#: Faces counter-clockwise seen from outside: x = -1, y = -1, z = -1, the slope x + y + z = -1.
FACES = ((0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2))

VOLUME = F(4, 3)
CENTER = (F(-1, 2), F(-1, 2), F(-1, 2))
CENTRAL = ((F(1, 5), F(-1, 15), F(-1, 15)),
           (F(-1, 15), F(1, 5), F(-1, 15)),
           (F(-1, 15), F(-1, 15), F(1, 5)))


@dataclass(frozen=True)
class Corner(polyhedron.ScaledPolyhedron):
    """The tetrahedron with the right-angled corner at (-sx, -sy, -sz)."""

    name = "corner"
    form = "corner or corner:SX,SY,SZ"
    mirror_symmetric = False
    VERTICES, FACES, VOLUME, CENTER, CENTRAL = VERTICES, FACES, VOLUME, CENTER, CENTRAL

    def inside(self, points) -> np.ndarray:
        """Boolean mask over points in the shape's own frame (closed set)."""
        p = polyhedron.as_points(points)
        sx, sy, sz = self.sx, self.sy, self.sz
        above = (p[:, 0] >= -sx) & (p[:, 1] >= -sy) & (p[:, 2] >= -sz)
        # x/sx + y/sy + z/sz ≤ -1, multiplied through by sx·sy·sz > 0.
        slope = p[:, 0] * (sy * sz) + p[:, 1] * (sx * sz) + p[:, 2] * (sx * sy) <= -(sx * sy * sz)
        return above & slope
