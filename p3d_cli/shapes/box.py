"""Box: the canonical cube [-1, 1]³ scaled to half-extents (sx, sy, sz) (docs/method.md, "Scale factors")."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as F

import numpy as np

from p3d_cli.shapes import polyhedron

#: Canonical vertices, index = 4·(x>0) + 2·(y>0) + (z>0).
VERTICES = tuple((x, y, z) for x in (-1, 1) for y in (-1, 1) for z in (-1, 1))
#: Quadrilateral faces, counter-clockwise seen from outside.
FACES = ((0, 1, 3, 2), (4, 6, 7, 5),      # x = -1, x = +1
         (0, 4, 5, 1), (2, 3, 7, 6),      # y = -1, y = +1
         (0, 2, 6, 4), (1, 5, 7, 3))      # z = -1, z = +1

# Closed forms of the canonical cube: V = 2³ = 8, centre 0 by symmetry, and
# ∫x² dV = ∫x² dx · 2 · 2 = (2/3)·4 = 8/3 (likewise y, z); ∫xy dV = 0 by symmetry.
VOLUME = F(8)
CENTER = (F(0), F(0), F(0))
CENTRAL = ((F(8, 3), F(0), F(0)), (F(0), F(8, 3), F(0)), (F(0), F(0), F(8, 3)))


@dataclass(frozen=True)
class Box(polyhedron.ScaledPolyhedron):
    """The box [-sx, sx] × [-sy, sy] × [-sz, sz]."""

    name = "box"
    form = "box or box:SX,SY,SZ"
    mirror_symmetric = True
    VERTICES, FACES, VOLUME, CENTER, CENTRAL = VERTICES, FACES, VOLUME, CENTER, CENTRAL

    def inside(self, points) -> np.ndarray:
        """Boolean mask: which points (shape's own frame) lie in the closed box."""
        p = np.abs(polyhedron.as_points(points))
        return (p[:, 0] <= self.sx) & (p[:, 1] <= self.sy) & (p[:, 2] <= self.sz)

