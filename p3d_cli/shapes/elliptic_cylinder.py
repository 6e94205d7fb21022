"""Elliptic cylinder: the canonical cylinder under any diagonal scale (spec ``ecylinder:A,B,H``).

The exact generalisation of the cylinder when sx = sy does not hold: moments are the
cylinder's constants through eq. 9 (exact for any diagonal scale, docs/method.md, "Scaling"). Bounds: the
solid is the Minkowski sum of its axis segment ``±h a`` (``a = R e_z``) and the elliptic disc
``{R S (u, v, 0) : u² + v² ≤ 1}``, whose support along world axis i is
``sqrt((R_i0 a)² + (R_i1 b)²)``; the half-extent is ``|a_i| h`` plus that. With a = b = r it
is the circular cylinder's ``|a_i| h + r sqrt(1 - a_i²)``.
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
from p3d_cli.shapes.unit_cylinder import CENTER, CENTRAL_PER_PI, VOLUME_PER_PI, unit_cylinder_triangles


@dataclass(frozen=True)
class EllipticCylinder(ShapeRecord):
    """The solid ``(x/a)² + (y/b)² ≤ 1, |z| ≤ h``.

    Attributes
    ----------
    a, b : float
        Semi-axes of the cross-section along x and y (positive).
    h : float
        Half-height along z (positive).
    """

    a: float = 1.0
    b: float = 1.0
    h: float = 1.0

    name = "ecylinder"
    form = "ecylinder or ecylinder:A,B,H (semi-axes A, B about z, half-height H)"
    mirror_symmetric = True
    polyhedral = False

    @property
    def scale(self) -> np.ndarray:
        return np.array([self.a, self.b, self.h], dtype=np.float64)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        return f"ecylinder:{self.a:g},{self.b:g},{self.h:g}"

    def scaled(self, scale) -> "EllipticCylinder":
        s = self.scale * np.asarray(scale, dtype=np.float64)
        return EllipticCylinder(*map(float, s))

    def moments(self) -> Moments:
        return scale_moments(canonical_moments(VOLUME_PER_PI, CENTER, CENTRAL_PER_PI, math.pi),
                             self.scale)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        half = (np.abs(r[:, 2]) * self.h
                + np.sqrt((r[:, 0] * self.a) ** 2 + (r[:, 1] * self.b) ** 2))
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        return Bounds(t - half, t + half)

    def inside(self, points) -> np.ndarray:
        p = polyhedron.as_points(points)
        return ((p[:, 0] / self.a) ** 2 + (p[:, 1] / self.b) ** 2 <= 1.0) & (np.abs(p[:, 2]) <= self.h)

    def tessellate(self, n: int) -> np.ndarray:
        """The scaled inscribed ``n``-gon prism."""
        return unit_cylinder_triangles(n) * self.scale
