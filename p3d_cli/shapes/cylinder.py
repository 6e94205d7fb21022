"""Cylinder: radius r about the z axis, z in [-h, h] (the Physics3D note's rule sx = sy = r, sz = h).

Closed forms of the canonical cylinder (r = 1, z ∈ [-1, 1]): V = π·1²·2 = 2π, centre 0,
``∫x² dV = 2 ∫₀^{2π}∫₀¹ ρ² cos²φ ρ dρ dφ = 2·π/4 = π/2`` (likewise y),
``∫z² dV = π ∫₋₁¹ z² dz = 2π/3``, products zero by symmetry.

Bounds (docs/method.md, "Rotated bounds"): the cylinder is the Minkowski sum of its axis segment
``±h a`` and its central disc, so along world axis i the half-extent is
``|a_i| h + r sqrt(1 - a_i²)`` with ``a = R e_z`` the world axis direction (evaluated as
``r sqrt(R_i0² + R_i1²)`` for the second term, which is the same for a rotation and does not
cancel when |a_i| ≈ 1).
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
from p3d_cli.shapes.elliptic_cylinder import EllipticCylinder
from p3d_cli.shapes.record import ShapeRecord, written
from p3d_cli.shapes.unit_cylinder import CENTER, CENTRAL_PER_PI, VOLUME_PER_PI, unit_cylinder_triangles

__all__ = ["Cylinder", "CENTER", "CENTRAL_PER_PI", "VOLUME_PER_PI"]



@dataclass(frozen=True)
class Cylinder(ShapeRecord):
    """The solid ``x² + y² ≤ r², |z| ≤ h``.

    Attributes
    ----------
    r : float
        Radius (positive).
    h : float
        Half-height (positive).
    """

    r: float = 1.0
    h: float = 1.0

    name = "cylinder"
    form = "cylinder or cylinder:R,R,H (radius R about z, half-height H)"
    mirror_symmetric = True
    polyhedral = False

    @classmethod
    def from_numbers(cls, text: str, numbers: list[float]) -> "Cylinder":
        """``cylinder:R,R,H``; unequal first two factors are refused (circles stay circles)."""
        if numbers[0] != numbers[1]:
            raise SpecError(text, "a cylinder (axis z) keeps sx = sy (circles stay circles)",
                            f"write cylinder:R,R,H, or ecylinder:{written(numbers)} for the elliptic cylinder")
        return cls(numbers[0], numbers[2])

    @property
    def scale(self) -> np.ndarray:
        return np.array([self.r, self.r, self.h], dtype=np.float64)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        return f"cylinder:{self.r:g},{self.r:g},{self.h:g}"

    def scaled(self, scale):
        """A cylinder when sx = sy; otherwise the exact generalisation, an ``EllipticCylinder``."""
        s = self.scale * np.asarray(scale, dtype=np.float64)
        if s[0] == s[1]:
            return Cylinder(float(s[0]), float(s[2]))
        return EllipticCylinder(*map(float, s))

    def moments(self) -> Moments:
        return scale_moments(canonical_moments(VOLUME_PER_PI, CENTER, CENTRAL_PER_PI, math.pi),
                             self.scale)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """Exact: half-extent i is ``|a_i| h + r sqrt(1 - a_i²)``, ``a = R e_z``."""
        r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        # Row i of R is a unit vector, so 1 - a_i² = R_i0² + R_i1². The sum of squares is
        # used because 1 - a_i² cancels catastrophically when |a_i| ≈ 1: for a_i = 1 - 2e-20
        # it rounds to 0 where the true value is 2e-10 (found by the hypothesis tests).
        half = np.abs(r[:, 2]) * self.h + self.r * np.sqrt(r[:, 0] ** 2 + r[:, 1] ** 2)
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        return Bounds(t - half, t + half)

    def inside(self, points) -> np.ndarray:
        p = polyhedron.as_points(points)
        return (p[:, 0] ** 2 + p[:, 1] ** 2 <= self.r * self.r) & (np.abs(p[:, 2]) <= self.h)

    def tessellate(self, n: int) -> np.ndarray:
        """An inscribed ``n``-gon prism (see ``unit_cylinder_triangles``), scaled."""
        return unit_cylinder_triangles(n) * self.scale
