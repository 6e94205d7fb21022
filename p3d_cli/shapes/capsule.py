"""Capsule: a cylinder of radius r about the z axis, z in [-h, h], closed by two hemispheres
(spec ``capsule:R,H``; H is the half-length of the cylindrical part, as MuJoCo's capsule
``size="R H"``). The points within distance r of the segment from (0, 0, -h) to (0, 0, h).

Closed forms (the cylinder part plus the two caps, which together make a ball of radius r
whose halves are moved by ±h along z):

- ``V = 2π r² h + (4/3) π r³``.
- Centre 0 by symmetry; products ``∫xy``, ``∫xz``, ``∫yz`` vanish by symmetry.
- ``∫x² dV = π r⁴ h / 2 + 4π r⁵ / 15``: the cylinder's ``π r² · 2h · r²/4`` plus the ball's
  ``4π r⁵/15`` (moving a cap along z does not change ``∫x²``); likewise ``∫y²``.
- ``∫z² dV = (2/3) π r² h³ + (4/3) π r³ h² + π r⁴ h + (4/15) π r⁵``: the cylinder's
  ``π r² ∫₋ₕʰ z² dz``, and for each cap (a hemisphere ``u ∈ [0, r]`` at ``z = h + u``)
  ``∫(h + u)² dV = h² (2π r³/3) + 2h (π r⁴/4) + 2π r⁵/15``, using the hemisphere's
  ``∫u dV = (3r/8)(2π r³/3)`` and half the ball's ``∫u² dV``.

A capsule is not the image of one canonical solid under a diagonal scale (r and h are free),
so its moments are written out here. A uniform scale keeps it a capsule; a non-uniform one
gives its exact generalisation, the capsule stretched by ``D = diag(stretch)`` (a cylinder of
elliptic section with semi-ellipsoidal caps), whose moments are the capsule's mapped by eq. 9.

Bounds (docs/method.md, "Rotated bounds"): the capsule is the Minkowski sum of its axis
segment ``±h e_z`` and the ball of radius r, and a linear map ``A = R D`` maps a Minkowski sum
to the sum of the images: the segment ``±h A e_z`` and the ellipsoid ``r A B``, whose support
along world axis i is ``r |row i of A|`` (as for the ellipsoid). So the half-extent is
``|A_i2| h + r |A_i|``; for ``D = E`` that is ``|a_i| h + r`` with ``a = R e_z``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from p3d_cli.geometry.moments import scale_moments
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes import polyhedron
from p3d_cli.shapes.polyhedron import check_segments
from p3d_cli.shapes.record import ShapeRecord


def capsule_moments(r: float, h: float) -> Moments:
    """The closed-form ``Moments`` of the capsule of radius ``r`` and half-length ``h``."""
    pi = math.pi
    volume = 2 * pi * r * r * h + 4 * pi * r ** 3 / 3
    cxx = pi * r ** 4 * h / 2 + 4 * pi * r ** 5 / 15
    czz = 2 * pi * r * r * h ** 3 / 3 + 4 * pi * r ** 3 * h * h / 3 + pi * r ** 4 * h + 4 * pi * r ** 5 / 15
    return Moments(volume, np.zeros(3), np.diag([cxx, cxx, czz]))


@dataclass(frozen=True)
class Capsule(ShapeRecord):
    """The solid within distance ``r`` of the segment ``(0, 0, ±h)``.

    Attributes
    ----------
    r : float
        Radius (positive).
    h : float
        Half-length of the cylindrical part (positive); the capsule spans ``|z| ≤ h + r``.
    stretch : three floats
        A diagonal scale applied to that capsule, ``(1, 1, 1)`` for a true capsule (a non-uniform
        ``scaled`` gives one; it is never a uniform factor other than 1, which goes into r, h).
    """

    r: float = 1.0
    h: float = 1.0
    stretch: tuple[float, float, float] = (1.0, 1.0, 1.0)

    name = "capsule"
    form = "capsule or capsule:R,H (radius R about z, H the half-length of the cylindrical part)"
    arity = (2,)
    scale_factors = False       # a radius and a half-length, not half-extents
    mirror_symmetric = True
    polyhedral = False

    def numbers(self) -> tuple[float, ...]:
        return (float(self.r), float(self.h))

    @property
    def scale(self) -> np.ndarray:
        """Half-extents of the bounding box."""
        return np.array([self.r, self.r, self.h + self.r], dtype=np.float64) * self.stretch

    @property
    def is_stretched(self) -> bool:
        return self.stretch != (1.0, 1.0, 1.0)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        base = f"capsule:{self.r:g},{self.h:g}"
        return base if not self.is_stretched else base + " stretched " + ",".join(f"{s:g}" for s in self.stretch)

    def scaled(self, scale) -> "Capsule":
        """A capsule for a uniform scale (of a true capsule); otherwise the stretched capsule."""
        s = np.asarray(self.stretch) * np.asarray(scale, dtype=np.float64).reshape(3)
        if np.all(s == s[0]):
            return Capsule(self.r * float(s[0]), self.h * float(s[0]))
        return Capsule(self.r, self.h, (float(s[0]), float(s[1]), float(s[2])))

    def moments(self) -> Moments:
        m = capsule_moments(self.r, self.h)
        return scale_moments(m, self.stretch) if self.is_stretched else m

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """Exact: half-extent i is ``|A_i2| h + r |A_i|`` with ``A = R diag(stretch)``."""
        a = (np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)) * self.stretch
        # For a rotation (no stretch) |A_i| = 1: use it exactly, as the rows' norms round.
        norms = np.sqrt(np.einsum("ij,ij->i", a, a)) if self.is_stretched else 1.0
        half = np.abs(a[:, 2]) * self.h + self.r * norms
        t = np.zeros(3) if translation is None else np.asarray(translation, dtype=np.float64)
        return Bounds(t - half, t + half)

    def inside(self, points) -> np.ndarray:
        p = polyhedron.as_points(points) / self.stretch
        # Distance to the axis segment: clamp z onto [-h, h].
        dz = p[:, 2] - np.clip(p[:, 2], -self.h, self.h)
        return p[:, 0] ** 2 + p[:, 1] ** 2 + dz * dz <= self.r * self.r

    def tessellate(self, n: int) -> np.ndarray:
        """An inscribed polyhedron: ``n`` segments around z, ``max(1, n // 4)`` stacks per cap.

        Returns
        -------
        (k, 3, 3) float64
            Counter-clockwise seen from outside; every vertex on the capsule's surface.
        """
        triangles = capsule_triangles(self.r, self.h, check_segments(n))
        return triangles * self.stretch if self.is_stretched else triangles


def capsule_triangles(r: float, h: float, n: int) -> np.ndarray:
    """The latitude-longitude capsule: the sphere's rings split at the equator and moved ±h.

    Ring ``k`` of the upper cap lies at polar angle ``θ_k`` in [0, π/2] about ``(0, 0, h)``,
    the lower cap's in [π/2, π] about ``(0, 0, -h)``; the two equator rings bound the
    cylindrical band. Poles are n copies of one point, so their degenerate triangles are
    dropped (as for the sphere).
    """
    m = max(1, n // 4)
    upper = np.pi / 2 * np.arange(m + 1) / m
    theta = np.concatenate([upper, upper + np.pi / 2])
    shift = np.concatenate([np.full(m + 1, h), np.full(m + 1, -h)])
    phi = 2 * np.pi * np.arange(n) / n
    rings = np.stack([r * np.outer(np.sin(theta), np.cos(phi)),
                      r * np.outer(np.sin(theta), np.sin(phi)),
                      np.repeat((r * np.cos(theta) + shift)[:, None], n, axis=1)], axis=-1)
    rings[0] = (0.0, 0.0, h + r)
    rings[-1] = (0.0, 0.0, -h - r)
    # The equator rings are exact (sin = 1, cos = 0), so the band's sides are vertical.
    rings[m, :, 2] = h
    rings[m + 1, :, 2] = -h
    j = np.arange(n)
    jn = (j + 1) % n
    last = len(rings) - 2
    tris = []
    for k in range(len(rings) - 1):
        top, bottom = rings[k], rings[k + 1]
        # Quad (t_j, b_j, b_j+1, t_j+1) runs down then east: its normal points outward.
        if k != last:
            tris.append(np.stack([top[j], bottom[j], bottom[jn]], axis=1))
        if k != 0:
            tris.append(np.stack([top[j], bottom[jn], top[jn]], axis=1))
    return np.concatenate(tris)
