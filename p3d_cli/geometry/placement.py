"""Placing a solid: a diagonal scale, then a rotation about the world origin, then a translation.

Mass properties are placed from the unplaced solid's moments: eq. 9 of the Physics3D note
(``p3d_cli.geometry.moments.scale_moments``) for the scale, ``C' = R C Rᵀ`` for the rotation (so
``I' = R I Rᵀ``), and the centre moved by the translation (docs/method.md, "Placement").
Bounds are placed exactly: shapes by their closed forms, triangles by projecting every corner.

Mirrors: a negative scale factor reflects the solid. A reflection reverses the orientation of
every face, so a mesh that was wound outward would come out wound inward and its signed
volume negative (eq. 4 gives ``V' = sx sy sz V``). p3d treats a mirrored part as the mirror
image of the solid, wound outward again: the winding is flipped back, which multiplies the
volume and the central second moments by ``sign(sx sy sz)``, so ``V' = |sx sy sz| V`` and
``C' = |det S| S C S`` (so ``I' = S I S`` for a pure reflection ``S = diag(±1)``). An
inward-wound input stays inward-wound (its volume stays negative), as it should.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any, Callable

import numpy as np

from p3d_cli.geometry.bounding import triangles_bounds
from p3d_cli.errors import UsageError
from p3d_cli.geometry.expansions import rounded_sums
from p3d_cli.geometry.moments import rotate_moments, scale_moments, translate_moments
from p3d_cli.results import Bounds, Moments


def check_scale(scale) -> np.ndarray:
    """``scale`` as ``(3,) float64`` (one number: uniform), or ``UsageError`` unless all three
    are finite and non-zero (negative factors mirror)."""
    s = np.ones(3) if scale is None else np.asarray(scale, dtype=np.float64).reshape(-1)
    if s.shape == (1,):
        s = np.repeat(s, 3)
    if s.shape != (3,) or not np.all(np.isfinite(s)) or not np.all(s != 0):
        raise UsageError("scale", f"{tuple(s.tolist())} is not one or three finite non-zero factors",
                         "give S or SX,SY,SZ, each positive, or negative to mirror the solid")
    return s


def mirror_signs(scale) -> np.ndarray | None:
    """The reflection ``diag(sign(s))`` of a scale as ``(3,)`` signs, or None when it mirrors nothing."""
    if scale is None or np.all(scale > 0):
        return None
    return np.sign(scale)


def flip_winding(moments: Moments) -> Moments:
    """The moments of the same solid with its winding reversed: signed ``V`` and ``C`` negated."""
    if moments.is_empty:
        return Moments(-moments.volume, None, None, moments.errors)
    return Moments(-moments.volume, moments.center, -moments.central, moments.errors)


@dataclass(frozen=True)
class Mirrored:
    """A shape reflected by ``diag(signs)`` (for shapes that are not mirror-symmetric: wedge,
    corner). It answers the shape protocol, so every road (closed forms, bounds, Monte Carlo's
    inside test and sampling box) sees the mirrored solid.

    Attributes
    ----------
    shape : Shape
        The shape before the reflection (positive scale factors).
    signs : (3,) float64
        ``±1`` per axis.
    """

    shape: Any
    signs: np.ndarray

    @property
    def name(self) -> str:
        return self.shape.name

    @property
    def polyhedral(self) -> bool:
        return self.shape.polyhedral

    @property
    def mirror_symmetric(self) -> bool:
        return self.shape.mirror_symmetric

    @property
    def scale(self) -> np.ndarray:
        return self.shape.scale

    def spec(self) -> str:
        return f"{self.shape.spec()} mirrored {','.join(f'{s:g}' for s in self.signs)}"

    def scaled(self, scale) -> "Mirrored":
        s = np.asarray(scale, dtype=np.float64)
        return Mirrored(self.shape.scaled(np.abs(s)), self.signs * np.sign(s))

    def moments(self) -> Moments:
        return place_moments(self.shape.moments(), self.signs)

    def bounds(self, rotation=None, translation=None) -> Bounds:
        r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
        # R M is orthogonal: every shape's bounds formula holds for it (they use the
        # matrix as a linear map, never its determinant).
        return self.shape.bounds(r * self.signs, translation)

    def inside(self, points) -> np.ndarray:
        return self.shape.inside(np.asarray(points, dtype=np.float64).reshape(-1, 3) * self.signs)

    def vertices(self) -> np.ndarray:
        return self.shape.vertices() * self.signs

    def triangles(self) -> np.ndarray:
        return self._outward(self.shape.triangles() * self.signs)

    def tessellate(self, n: int) -> np.ndarray:
        return self._outward(self.shape.tessellate(n) * self.signs)

    def _outward(self, triangles: np.ndarray) -> np.ndarray:
        # A reflection (odd number of -1) turns every face inward: swap two corners back.
        # Two -1 are a half turn, which keeps the winding.
        return triangles[:, [0, 2, 1]] if np.prod(self.signs) < 0 else triangles


@dataclass(frozen=True)
class PlacementErrors:
    """Bounds on the absolute error of a placement's stored floats against the exact placement
    they stand for: the rounding of composing placements (``then``) and of unit factors
    (docs/accuracy.md, "Placed parts and assemblies"). Entries are 0 where a value is exact.

    Attributes
    ----------
    scale : (3,) float64
    rotation : (3, 3) float64
        Per entry, against the exact product of the (float) rotations composed.
    translation : (3,) float64
    """

    scale: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray

    @staticmethod
    def of(placement: "Placement") -> "PlacementErrors":
        """``placement``'s errors, zeros where it has none."""
        if placement.errors is not None:
            return placement.errors
        return PlacementErrors(np.zeros(3), np.zeros((3, 3)), np.zeros(3))


@dataclass(frozen=True)
class Placement:
    """Scale, then rotation about the origin, then translation.

    Attributes
    ----------
    scale : (3,) float64 or None
        Non-zero diagonal scale factors (one number is a uniform scale); a negative factor
        mirrors the solid (see the module's note on winding).
    rotation : (3, 3) float64 or None
        A proper rotation matrix (``p3d_cli.geometry.rotation``).
    translation : (3,) float64 or None
    errors : PlacementErrors or None
        How far these floats may be from the exact placement they stand for, when they were
        computed (composed placements, unit factors); None: they are exact as given.
    """

    scale: np.ndarray | None = None
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None
    errors: "PlacementErrors | None" = None

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
        """The placed solid's moments (eq. 9, then ``R C Rᵀ``, then the centre moved), their
        error bounds grown by the placement's own (``errors``)."""
        return place_moments(moments, self.scale, self.rotation, self.translation, self.errors)

    def shape(self, shape):
        """The shape after the scale (a sphere or cylinder becomes its exact generalisation; a
        mirrored shape that is not ``mirror_symmetric``, as a wedge or corner, a ``Mirrored`` one)."""
        if self.scale is None:
            return shape
        signs = mirror_signs(self.scale)
        scaled = shape.scaled(np.abs(self.scale))
        if signs is None or scaled.mirror_symmetric:     # the shape class declares it
            return scaled
        return Mirrored(scaled, signs)

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


def place_moments(moments: Moments, scale=None, rotation=None, translation=None,
                  errors: PlacementErrors | None = None) -> Moments:
    """Moments after a diagonal scale, a rotation about the origin and a translation.

    Parameters
    ----------
    moments : Moments
    scale : (3,) array_like, optional
        Eq. 9: exact for any diagonal scale (docs/method.md, "Scaling"). A mirroring scale
        (``sx sy sz < 0``) also flips the winding back (the module's note), so an outward solid
        keeps a positive volume.
    rotation : (3, 3) array_like, optional
    translation : (3,) array_like, optional
    errors : PlacementErrors, optional
        Bounds on how far ``scale``, ``rotation`` and ``translation`` are from the exact
        placement (a composed one's rounding): they enter the moments' error bounds.
    """
    e = errors
    if scale is not None:
        s = check_scale(scale)
        moments = scale_moments(moments, s, None if e is None else e.scale)
        if s[0] * s[1] * s[2] < 0:
            moments = flip_winding(moments)
    if rotation is not None:
        moments = rotate_moments(moments, rotation, None if e is None else e.rotation)
    if translation is not None:
        moments = translate_moments(moments, translation, None if e is None else e.translation)
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


def then(first: Placement, second: Placement) -> Placement:
    """The placement ``second ∘ first`` (``first`` applied, then ``second``), which must again be
    scale-rotate-translate: so ``second``'s scale must be uniform up to mirrors (``|sx| = |sy| =
    |sz|``; a non-uniform scale after a rotation is a shear, which no diagonal scale gives).

    ``R2 S2 (R1 S1 p + t1) + t2``, with ``S2 = s M`` (``M`` a reflection): ``M R1 = (M R1 M) M``
    and ``M R1 M`` is a rotation, so this is ``R S p + t`` with ``R = R2 M R1 M``,
    ``S = s M S1`` and ``t = R2 S2 t1 + t2``.

    Every entry of ``R``, ``S`` and ``t`` is its exact value rounded once (``rounded_sum``), so
    a part placed far out and brought back by an outer placement keeps its accuracy; the
    result's ``errors`` hold those roundings plus the inputs' own errors carried through
    (docs/accuracy.md, "Placed parts and assemblies").

    Raises
    ------
    UsageError
        ``second``'s scale is not uniform.
    """
    s2 = np.ones(3) if second.scale is None else second.scale
    if not np.all(np.abs(s2) == abs(s2[0])):
        raise UsageError("scale", f"{tuple(s2.tolist())} is not uniform, and it would apply after "
                         "a rotation inside (a shear)", "give one factor (a negative one mirrors)")
    signs = np.sign(s2)
    e1, e2 = PlacementErrors.of(first), PlacementErrors.of(second)
    r1 = np.eye(3) if first.rotation is None else first.rotation
    r2 = np.eye(3) if second.rotation is None else second.rotation
    s1 = np.ones(3) if first.scale is None else first.scale
    t1 = np.zeros(3) if first.translation is None else first.translation
    t2 = np.zeros(3) if second.translation is None else second.translation
    m1 = signs[:, None] * r1 * signs                    # M R1 M: sign flips, exact
    # With either rotation the identity the product is the other, exactly.
    rotation, rotation_error = (m1, np.zeros((3, 3))) if second.rotation is None else (r2, np.zeros((3, 3)))
    if first.rotation is not None and second.rotation is not None:
        r2l, m1l = r2.tolist(), m1.tolist()
        rotation, rotation_error = rounded_sums([[[(r2l[i][k], m1l[k][j]) for k in range(3)] for j in range(3)]
                                                   for i in range(3)])
    scale, scale_error = rounded_sums([[(a, b)] for a, b in zip(s2.tolist(), s1.tolist())])
    r2l, s2l, t1l, t2l = r2.tolist(), s2.tolist(), t1.tolist(), t2.tolist()
    if second.rotation is None:
        translation, translation_error = rounded_sums([[(s2l[i], t1l[i]), (t2l[i],)] for i in range(3)])
    else:
        translation, translation_error = rounded_sums([[(r2l[i][k], s2l[k], t1l[k]) for k in range(3)]
                                                         + [(t2l[i],)] for i in range(3)])
    # The inputs' own errors, carried through the products (first order and the product of
    # errors, so nothing is dropped), rounded up by _UP.
    a1, a2 = np.abs(m1), np.abs(r2)
    rotation_error = rotation_error + _UP * (a2 @ e1.rotation + e2.rotation @ (a1 + e1.rotation))
    scale_error = scale_error + _UP * (np.abs(s2) * e1.scale + e2.scale * (np.abs(s1) + e1.scale))
    x = np.abs(s2) * np.abs(t1)
    ex = np.abs(s2) * e1.translation + e2.scale * (np.abs(t1) + e1.translation)
    translation_error = translation_error + _UP * (a2 @ ex + e2.rotation @ (x + ex) + e2.translation)
    return _placement(scale, rotation, translation,
                      PlacementErrors(scale_error, rotation_error, translation_error))


def scaling(factor: float, error: float = 0.0) -> Placement:
    """The uniform scale by ``factor`` (a unit factor), ``error`` off its exact value."""
    errors = None if error == 0 else PlacementErrors(np.full(3, error), np.zeros((3, 3)), np.zeros(3))
    return Placement(scale=np.full(3, factor), errors=errors)


def converted(placement: Placement, factor: Fraction, *, coordinates: bool = False) -> Placement:
    """``placement`` written in a length unit ``factor`` times the output unit (the exact ratio
    of the units, ``p3d_cli.units.exact_length``), carried into the output unit: the translation
    becomes ``f t``; with ``coordinates``, the solid's own coordinates are in that unit too, so
    the scale becomes ``f S`` (a uniform scale commutes with rotations, so nothing else changes).
    Each product is the exact one rounded once (``0.3 mm`` is the float nearest 0.0003 m), and
    its rounding, known exactly, enters ``errors`` with the inputs' own errors times ``f``.
    """
    from p3d_cli.units import exact_products

    factor = Fraction(factor)
    if factor == 1:
        return placement
    e = PlacementErrors.of(placement)
    f = abs(float(factor)) * _UP
    translation, translation_error = placement.translation, e.translation
    if translation is not None:
        translation, rounding = exact_products(translation, factor)
        translation_error = rounding + e.translation * f
    scale, scale_error = placement.scale, e.scale
    if coordinates:
        scale, rounding = exact_products(np.ones(3) if scale is None else scale, factor)
        scale_error = rounding + e.scale * f
    return _placement(scale, placement.rotation, translation,
                      PlacementErrors(scale_error, e.rotation, translation_error))


def prescaled(placement: Placement, exponent: int, where: str = "placement") -> Placement:
    """``placement`` applied after a uniform scale by ``2**exponent``: its scale factors (and
    their errors) times that power of two, which is exact unless the product leaves float64's
    normal range (then ``RangeError``: the placed part is too small or too large).

    Raises
    ------
    RangeError
    """
    if exponent == 0:
        return placement
    e = PlacementErrors.of(placement)
    scale = np.ldexp(np.ones(3) if placement.scale is None else placement.scale, exponent)
    if not np.all(np.isfinite(scale)) or np.any(np.abs(scale) < np.finfo(np.float64).tiny):
        from p3d_cli.errors import RangeError

        raise RangeError(where, "the part is too " + ("small" if exponent < 0 else "large") + " for float64 "
                         "even after the scale given", "measure it in a unit nearer its size")
    errors = None if placement.errors is None else PlacementErrors(np.ldexp(e.scale, exponent), e.rotation,
                                                                   e.translation)
    return Placement(scale, placement.rotation, placement.translation, errors)


#: Rounds a bound's own float arithmetic (a few operations on non-negative terms) upward.
_UP = 1.0 + 2.0 ** -40


def _placement(scale, rotation, translation, errors: PlacementErrors) -> Placement:
    """A placement, dropping the parts that are the identity and exactly so."""
    exact = lambda e: not np.any(e)  # noqa: E731
    if scale is not None and np.all(scale == 1) and exact(errors.scale):
        scale = None
    if rotation is not None and np.array_equal(rotation, np.eye(3)) and exact(errors.rotation):
        rotation = None
    if translation is not None and not np.any(translation) and exact(errors.translation):
        translation = None
    none = exact(errors.scale) and exact(errors.rotation) and exact(errors.translation)
    return Placement(scale, rotation, translation, None if none else errors)
