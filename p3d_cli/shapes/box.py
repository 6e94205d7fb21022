"""Box: the canonical cube [-1, 1]³ scaled to half-extents (sx, sy, sz) (FACTS.md)."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction as F

import numpy as np

from p3d_cli.moments import scale_moments
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes import polyhedron
from p3d_cli.shapes.closed_form import canonical_moments

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
class Box:
    """The box [-sx, sx] × [-sy, sy] × [-sz, sz].

    Attributes
    ----------
    sx, sy, sz : float
        Half-extents (positive).
    """

    sx: float = 1.0
    sy: float = 1.0
    sz: float = 1.0

    name = "box"
    polyhedral = True

    @property
    def scale(self) -> np.ndarray:
        return np.array([self.sx, self.sy, self.sz], dtype=np.float64)

    def spec(self) -> str:
        return f"box:{self.sx:g},{self.sy:g},{self.sz:g}"

    def scaled(self, scale) -> "Box":
        """The box after a further diagonal scale (still a box)."""
        s = self.scale * np.asarray(scale, dtype=np.float64)
        return Box(*map(float, s))

    def moments(self) -> Moments:
        """Exact volume moments (eq. 4-9 applied to the canonical constants)."""
        return scale_moments(canonical_moments(VOLUME, CENTER, CENTRAL), self.scale)

    def vertices(self) -> np.ndarray:
        """The 8 corners, ``(8, 3) float64``."""
        return polyhedron.scaled_vertices(VERTICES, self.scale)

    def triangles(self) -> np.ndarray:
        """12 outward-wound triangles, ``(12, 3, 3) float64``."""
        return polyhedron.face_triangles(self.vertices(), FACES)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """Exact axis-aligned box of ``R x + t`` over the solid (eq. 10)."""
        return polyhedron.projected_bounds(self.vertices(), rotation, translation)

    def inside(self, points) -> np.ndarray:
        """Boolean mask: which points (shape's own frame) lie in the closed box."""
        p = np.abs(polyhedron.as_points(points))
        return (p[:, 0] <= self.sx) & (p[:, 1] <= self.sy) & (p[:, 2] <= self.sz)

