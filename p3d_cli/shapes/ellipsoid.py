"""Ellipsoid: the unit ball under any diagonal scale (spec ``ellipsoid:A,B,C``).

The exact generalisation of the sphere when sx = sy = sz does not hold: eq. 9 is exact for
any diagonal scale (docs/method.md, "Scaling"), so its moments are the unit ball's constants scaled. Its
bounds have a closed form too: the support function of ``{M u : |u| ≤ 1}`` in direction e
is ``|Mᵀ e|``, so with ``M = R S`` the half-extent along world axis i is the length of row
i of ``R S``: ``sqrt(Σⱼ (R_ij sⱼ)²)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from p3d_cli.geometry.moments import scale_moments
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes import polyhedron
from p3d_cli.shapes.closed_form import canonical_moments
from p3d_cli.shapes.record import ShapeRecord
from p3d_cli.shapes.unit_ball import CENTER, CENTRAL_PER_PI, VOLUME_PER_PI, unit_sphere_triangles


@dataclass(frozen=True)
class Ellipsoid(ShapeRecord):
    """The solid ``(x/a)² + (y/b)² + (z/c)² ≤ 1``.

    Attributes
    ----------
    a, b, c : float
        Semi-axes along x, y, z (positive).
    """

    a: float = 1.0
    b: float = 1.0
    c: float = 1.0

    name = "ellipsoid"
    form = "ellipsoid or ellipsoid:A,B,C (semi-axes)"
    mirror_symmetric = True
    polyhedral = False

    @property
    def scale(self) -> np.ndarray:
        return np.array([self.a, self.b, self.c], dtype=np.float64)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        return f"ellipsoid:{self.a:g},{self.b:g},{self.c:g}"

    def scaled(self, scale) -> "Ellipsoid":
        s = self.scale * np.asarray(scale, dtype=np.float64)
        return Ellipsoid(*map(float, s))

    def moments(self) -> Moments:
        return scale_moments(canonical_moments(VOLUME_PER_PI, CENTER, CENTRAL_PER_PI, math.pi),
                             self.scale)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """Exact: half-extent i is ``|row i of R S|``."""
        m = np.diag(self.scale) if rotation is None else np.asarray(rotation, dtype=np.float64) * self.scale
        half = np.sqrt(np.einsum("ij,ij->i", m, m))
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        return Bounds(t - half, t + half)

    def inside(self, points) -> np.ndarray:
        q = polyhedron.as_points(points) / self.scale
        return np.einsum("ij,ij->i", q, q) <= 1.0

    def tessellate(self, n: int) -> np.ndarray:
        """The scaled latitude-longitude sphere of ``n`` segments (vertices on the surface)."""
        return unit_sphere_triangles(n) * self.scale
