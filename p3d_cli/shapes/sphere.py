"""Sphere: the unit ball scaled by r in every direction (the Physics3D note's rule sx = sy = sz).

Closed forms of the unit ball: V = 4π/3, centre 0, and by symmetry
``∫x² dV = (1/3) ∫|r|² dV = (1/3) ∫₀¹ 4π r⁴ dr = 4π/15`` (likewise y, z), ``∫xy dV = 0``.
Bounds under any rotation are ``t ± r`` (the Physics3D note's section 1.2.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from p3d_cli.geometry.moments import scale_moments
from p3d_cli.errors import SpecError
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes import polyhedron
from p3d_cli.shapes.closed_form import canonical_moments
from p3d_cli.shapes.ellipsoid import Ellipsoid
from p3d_cli.shapes.record import ShapeRecord, written
from p3d_cli.shapes.unit_ball import CENTER, CENTRAL_PER_PI, VOLUME_PER_PI, unit_sphere_triangles

__all__ = ["Sphere", "CENTER", "CENTRAL_PER_PI", "VOLUME_PER_PI"]


@dataclass(frozen=True)
class Sphere(ShapeRecord):
    """The ball of radius ``r`` about the origin.

    Attributes
    ----------
    r : float
        Radius (positive).
    """

    r: float = 1.0

    name = "sphere"
    form = "sphere, sphere:R or sphere:R,R,R"
    arity = (1, 3)
    mirror_symmetric = True
    polyhedral = False

    @classmethod
    def from_numbers(cls, text: str, numbers: list[float]) -> "Sphere":
        """``sphere:R``, or three equal factors (unequal ones are refused: circles stay circles)."""
        if len(numbers) == 3 and not numbers[0] == numbers[1] == numbers[2]:
            raise SpecError(text, "a sphere keeps sx = sy = sz (circles stay circles)",
                            f"write sphere:R, or ellipsoid:{written(numbers)} for the ellipsoid")
        return cls(numbers[0])

    def numbers(self) -> tuple[float, ...]:
        return (float(self.r),)

    @property
    def scale(self) -> np.ndarray:
        return np.full(3, self.r, dtype=np.float64)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        return f"sphere:{self.r:g}"

    def scaled(self, scale):
        """A sphere for a uniform scale; otherwise the exact generalisation, an ``Ellipsoid``."""
        s = self.scale * np.asarray(scale, dtype=np.float64)
        if s[0] == s[1] == s[2]:
            return Sphere(float(s[0]))
        return Ellipsoid(*map(float, s))

    def moments(self) -> Moments:
        return scale_moments(canonical_moments(VOLUME_PER_PI, CENTER, CENTRAL_PER_PI, math.pi),
                             self.scale)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """``t ± r`` whatever the rotation."""
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        return Bounds(t - self.r, t + self.r)

    def inside(self, points) -> np.ndarray:
        p = polyhedron.as_points(points)
        return np.einsum("ij,ij->i", p, p) <= self.r * self.r

    def tessellate(self, n: int) -> np.ndarray:
        """An inscribed polyhedron of ``n`` segments, ``(k, 3, 3) float64``, wound outward.

        See ``unit_sphere_triangles``.
        """
        return unit_sphere_triangles(n) * self.scale
