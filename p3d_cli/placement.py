"""Placing a solid: a diagonal scale, then a rotation about the world origin, then a translation.

Mass properties are placed from the unplaced solid's moments: eq. 9 of the Physics3D note
(``p3d_cli.moments.scale_moments``) for the scale, ``C' = R C Rᵀ`` for the rotation (so
``I' = R I Rᵀ``), and the centre moved by the translation (docs/method.md, "Placement").
Bounds are placed exactly: shapes by their closed forms, triangles by projecting every corner.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np

from p3d_cli.bounding import triangles_bounds
from p3d_cli.errors import UsageError
from p3d_cli.io.source import MeshSource
from p3d_cli.moments import rotate_moments, scale_moments, translate_moments
from p3d_cli.results import Bounds, Moments


def check_scale(scale) -> np.ndarray:
    """``scale`` as ``(3,) float64``, or ``UsageError`` unless all three are finite and > 0."""
    s = np.ones(3) if scale is None else np.asarray(scale, dtype=np.float64).reshape(-1)
    if s.shape != (3,) or not np.all(np.isfinite(s)) or not np.all(s > 0):
        raise UsageError("scale", f"{tuple(s.tolist())} is not three positive factors",
                         "give SX,SY,SZ > 0 (half-extent multipliers; p3d does not mirror)")
    return s


@dataclass(frozen=True)
class Placement:
    """Scale, then rotation about the origin, then translation.

    Attributes
    ----------
    scale : (3,) float64 or None
        Positive diagonal scale factors.
    rotation : (3, 3) float64 or None
        A proper rotation matrix (``p3d_cli.rotation``).
    translation : (3,) float64 or None
    """

    scale: np.ndarray | None = None
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.scale is not None:
            object.__setattr__(self, "scale", check_scale(self.scale))
        if self.rotation is not None:
            object.__setattr__(self, "rotation", np.asarray(self.rotation, dtype=np.float64).reshape(3, 3))
        if self.translation is not None:
            object.__setattr__(self, "translation", np.asarray(self.translation, dtype=np.float64).reshape(3))

    def describe(self) -> dict:
        """The placement for the record: only the parts that were given."""
        parts = {"scale": self.scale, "rotation": self.rotation, "translation": self.translation}
        return {name: value for name, value in parts.items() if value is not None}

    @property
    def is_identity(self) -> bool:
        return self.scale is None and self.rotation is None and self.translation is None

    def moments(self, moments: Moments) -> Moments:
        """The placed solid's moments (eq. 9, then ``R C Rᵀ``, then the centre moved)."""
        return place_moments(moments, self.scale, self.rotation, self.translation)

    def shape(self, shape):
        """The shape after the scale (a sphere or cylinder becomes its exact generalisation)."""
        return shape if self.scale is None else shape.scaled(self.scale)

    def shape_bounds(self, shape) -> Bounds:
        """Exact bounds of the placed shape (closed forms or vertex projection)."""
        return self.shape(shape).bounds(self.rotation, self.translation)

    def triangles_bounds(self, blocks) -> Bounds:
        """Exact bounds of the placed triangles (vertex projection)."""
        return triangles_bounds(blocks, self.scale, self.rotation, self.translation)

    def points(self, points: np.ndarray) -> np.ndarray:
        """``R (S p) + t`` for rows ``p`` of a ``(k, 3)`` array."""
        out = np.asarray(points, dtype=np.float64)
        if self.scale is not None:
            out = out * self.scale
        if self.rotation is not None:
            out = out @ self.rotation.T
        if self.translation is not None:
            out = out + self.translation
        return out

    def inside(self, inside: Callable[[np.ndarray], np.ndarray]) -> Callable[[np.ndarray], np.ndarray]:
        """The inside test of the rotated and moved solid, from the (already scaled) solid's."""
        if self.rotation is None and self.translation is None:
            return inside
        rot = np.eye(3) if self.rotation is None else self.rotation
        shift = np.zeros(3) if self.translation is None else self.translation
        # World point p = R q + t  <=>  q = Rᵀ (p - t); row vectors: q = (p - t) R.
        return lambda p: inside((p - shift) @ rot)


#: The placement that changes nothing.
IDENTITY = Placement()


def place_moments(moments: Moments, scale=None, rotation=None, translation=None) -> Moments:
    """Moments after a diagonal scale, a rotation about the origin and a translation.

    Parameters
    ----------
    moments : Moments
    scale : (3,) array_like, optional
        Eq. 9: exact for any diagonal scale (docs/method.md, "Scaling").
    rotation : (3, 3) array_like, optional
    translation : (3,) array_like, optional
    """
    if scale is not None:
        moments = scale_moments(moments, check_scale(scale))
    if rotation is not None:
        moments = rotate_moments(moments, rotation)
    if translation is not None:
        moments = translate_moments(moments, translation)
    return moments


def placed_bounds(shape_or_triangles, scale=None, rotation=None, translation=None) -> Bounds:
    """Exact axis-aligned bounds of a shape or a mesh after scale, rotation, translation.

    Parameters
    ----------
    shape_or_triangles : Shape, or (n, 3, 3) array, or iterable of triangle blocks
    scale : (3,) array_like, optional
        Diagonal scale in the solid's own frame (applied first, about the origin).
    rotation : (3, 3) array_like, optional
        Applied second, about the world origin.
    translation : (3,) array_like, optional
        Applied last.

    Returns
    -------
    Bounds
    """
    placement = Placement(scale, rotation, translation)
    if hasattr(shape_or_triangles, "bounds") and hasattr(shape_or_triangles, "scaled"):
        return placement.shape_bounds(shape_or_triangles)
    return placement.triangles_bounds(shape_or_triangles)


def watch_bounds(mesh: MeshSource, placement: Placement) -> tuple[MeshSource, Callable[[], Bounds | None]]:
    """``mesh`` with its blocks also projected as they stream past, and a getter for the bounds.

    One pass serves both the integrals and the placed bounds, so standard input (which reads
    once) and large files are not read twice.
    """
    seen: list[Bounds] = []
    if mesh.tetrahedra is not None:
        tetrahedra = np.asarray(mesh.tetrahedra)
        return mesh, lambda: placement.triangles_bounds(tetrahedra)

    def blocks() -> Iterator[np.ndarray]:
        seen.clear()
        for block in mesh.read_blocks():
            if len(block):
                seen.append(placement.triangles_bounds(block))
            yield block

    def bounds() -> Bounds | None:
        if not seen:
            return None
        return Bounds(np.min([b.min for b in seen], axis=0), np.max([b.max for b in seen], axis=0))

    return dataclasses.replace(mesh, read_blocks=blocks), bounds
