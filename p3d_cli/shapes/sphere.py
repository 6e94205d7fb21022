"""Sphere: the unit ball scaled by r in every direction (the note's rule sx = sy = sz).

Closed forms of the unit ball: V = 4π/3, centre 0, and by symmetry
``∫x² dV = (1/3) ∫|r|² dV = (1/3) ∫₀¹ 4π r⁴ dr = 4π/15`` (likewise y, z), ``∫xy dV = 0``.
Bounds under any rotation are ``t ± r`` (the note's section 1.2.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction as F

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.moments import scale_moments
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes import polyhedron
from p3d_cli.shapes.closed_form import canonical_moments

#: Canonical constants, as rational multiples of π.
VOLUME_PER_PI = F(4, 3)
CENTER = (F(0), F(0), F(0))
CENTRAL_PER_PI = ((F(4, 15), F(0), F(0)), (F(0), F(4, 15), F(0)), (F(0), F(0), F(4, 15)))

#: Fewest segments ``tessellate`` accepts (a triangle's worth around the axis).
MIN_SEGMENTS = 3


@dataclass(frozen=True)
class Sphere:
    """The ball of radius ``r`` about the origin.

    Attributes
    ----------
    r : float
        Radius (positive).
    """

    r: float = 1.0

    name = "sphere"
    polyhedral = False

    @property
    def scale(self) -> np.ndarray:
        return np.full(3, self.r, dtype=np.float64)

    def spec(self) -> str:
        return f"sphere:{self.r:g}"

    def scaled(self, scale):
        """A sphere for a uniform scale; otherwise the exact generalisation, an ``Ellipsoid``."""
        s = self.scale * np.asarray(scale, dtype=np.float64)
        if s[0] == s[1] == s[2]:
            return Sphere(float(s[0]))
        from p3d_cli.shapes.ellipsoid import Ellipsoid
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


def check_segments(n) -> int:
    """``n`` as a segment count, or ``UsageError``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < MIN_SEGMENTS:
        raise UsageError("--tessellate", f"{n!r} is not a segment count",
                         f"give a whole number of at least {MIN_SEGMENTS}")
    return int(n)


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
    n = check_segments(n)
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
