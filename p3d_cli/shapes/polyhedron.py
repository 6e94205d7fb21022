"""Pure functions shared by the polyhedral shape classes (box, wedge, corner).

A polyhedral class is a list of canonical vertices in [-1, 1]³ and faces wound
counter-clockwise seen from outside. Its placed bounds are exact by vertex projection
(the Physics3D note's eq. 10, generalised from the box's 8 corners to any vertex list): a
linear map sends the convex hull of the vertices to the convex hull of their images, and
a box around a convex hull is attained at vertices.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Callable, ClassVar

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.geometry.bounding import projected_bounds
from p3d_cli.geometry.moments import scale_moments
from p3d_cli.results import Bounds, Moments
from p3d_cli.shapes.closed_form import canonical_moments
from p3d_cli.shapes.record import ShapeRecord


def scaled_vertices(vertices, scale) -> np.ndarray:
    """Canonical vertices ``(k, 3)`` mapped by the diagonal scale: ``(k, 3) float64``."""
    return np.asarray(vertices, dtype=np.float64) * np.asarray(scale, dtype=np.float64)


def face_triangles(vertices: np.ndarray, faces) -> np.ndarray:
    """Triangles ``(n, 3, 3)`` from polygon faces (index lists, fanned from their first corner)."""
    tris = []
    for face in faces:
        for k in range(1, len(face) - 1):
            tris.append((face[0], face[k], face[k + 1]))
    return np.asarray(vertices, dtype=np.float64)[np.asarray(tris)]


def as_points(points) -> np.ndarray:
    """Points as ``(n, 3) float64`` (a single point becomes one row)."""
    return np.asarray(points, dtype=np.float64).reshape(-1, 3)


@dataclass(frozen=True)
class ScaledPolyhedron(ShapeRecord):
    """What box, wedge and corner share: canonical constants in [-1, 1]³, scaled.

    A subclass sets the class attributes ``name``, ``form``, ``mirror_symmetric``
    (``p3d_cli.shapes.record``), ``VERTICES`` (canonical corners), ``FACES``
    (wound counter-clockwise seen from outside), ``VOLUME``, ``CENTER``, ``CENTRAL`` (exact
    ``Fraction`` constants of the canonical solid) and defines its own ``inside``.

    Attributes
    ----------
    sx, sy, sz : float
        Half-extents of the bounding box (positive).
    """

    sx: float = 1.0
    sy: float = 1.0
    sz: float = 1.0

    polyhedral = True
    # Each subclass states its canonical solid (class constants, not dataclass fields).
    VOLUME: ClassVar[Fraction]
    CENTER: ClassVar[tuple]
    CENTRAL: ClassVar[tuple]
    VERTICES: ClassVar[tuple]
    FACES: ClassVar[tuple]

    @property
    def scale(self) -> np.ndarray:
        return np.array([self.sx, self.sy, self.sz], dtype=np.float64)

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the shape (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def spec(self) -> str:
        return f"{self.name}:{self.sx:g},{self.sy:g},{self.sz:g}"

    def scaled(self, scale):
        """The same class after a further diagonal scale."""
        s = self.scale * np.asarray(scale, dtype=np.float64)
        return type(self)(*map(float, s))

    def moments(self) -> Moments:
        """Exact volume moments: eq. 4-9 applied to the canonical constants."""
        return scale_moments(canonical_moments(self.VOLUME, self.CENTER, self.CENTRAL), self.scale)

    def vertices(self) -> np.ndarray:
        """The corners, ``(k, 3) float64``, in the order of ``VERTICES``."""
        return scaled_vertices(self.VERTICES, self.scale)

    def triangles(self) -> np.ndarray:
        """Outward-wound triangles, ``(n, 3, 3) float64``."""
        return face_triangles(self.vertices(), self.FACES)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        """Exact axis-aligned box of ``R x + t`` over the solid (eq. 10)."""
        return projected_bounds(self.vertices(), rotation, translation)


#: Fewest segments a tessellation accepts (a triangle's worth around the axis).
MIN_SEGMENTS = 3
#: Most triangles a tessellation may have: 2M triangles are 144 MB of float64 corners, and the
#: integrals need a few times that; the error at this size (below 1e-11 for the sphere) is far
#: under anything a tessellation is used to show.
MAX_TRIANGLES = 2_000_000


def check_segments(n, triangles: Callable[[int], int] = lambda n: n) -> int:
    """``n`` as a tessellation's segment count, or ``UsageError``.

    Parameters
    ----------
    n : int
    triangles : callable
        The triangle count ``n`` segments give: refused above ``MAX_TRIANGLES`` before any
        memory is asked for.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < MIN_SEGMENTS:
        raise UsageError("tessellate", f"{n!r} is not a segment count",
                         f"give a whole number of at least {MIN_SEGMENTS}")
    count = triangles(int(n))
    if count > MAX_TRIANGLES:
        raise UsageError("tessellate", f"{n} segments would make {count:,} triangles, over the limit of "
                         f"{MAX_TRIANGLES:,}", "give fewer segments (the error falls as 1/N²)")
    return int(n)
