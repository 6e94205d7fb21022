"""Pure functions on ``Moments``: placing a solid (scale, rotate, translate).

Central second moments ``C = ∫ (x - c)(x - c)ᵀ dV`` make these exact and stable:
a diagonal scale ``S`` maps ``C`` to ``det(S) · S C S`` (the Physics3D note's eq. 8-9, written
for the convention-free second moments), a rotation ``R`` maps it to ``R C Rᵀ``, and a
translation leaves it unchanged; only the centre moves.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import RangeError
from p3d_cli.results import MomentErrors, Moments

_EPS = float(np.finfo(np.float64).eps)
#: Rounds a bound's own arithmetic (a few operations on non-negative terms) upward.
_UP = 1.0 + 2.0 ** -40


def scale_moments(moments: Moments, scale, scale_error=None) -> Moments:
    """Moments of the solid after the diagonal scale ``x -> (sx x, sy y, sz z)``.

    Parameters
    ----------
    moments : Moments
    scale : (3,) array_like of float
        Scale factors; negative factors mirror the solid (and so negate its signed volume).
    scale_error : (3,) array_like of float, optional
        Bounds on how far each factor is from its exact value (a unit factor's rounding).

    Returns
    -------
    Moments
        ``V' = sx sy sz V`` (eq. 4), ``c' = S c`` (eq. 5), ``C'_ij = sx sy sz si sj C_ij`` (eq. 8-9).
    """
    s = np.asarray(scale, dtype=np.float64).reshape(3)
    det = float(s[0] * s[1] * s[2])
    outer = np.outer(s, s)
    volume = moments.volume * det
    if moments.is_empty:
        return Moments(volume, None, None, _scaled_errors(moments, s, det, outer, volume, None, scale_error))
    central = moments.central * outer * det
    return Moments(volume, moments.center * s, central,
                   _scaled_errors(moments, s, det, outer, volume, central, scale_error))


def _scaled_errors(moments, s, det, outer, volume, central, scale_error):
    errors = moments.errors
    if errors is None:
        return None
    # The factors' own errors, relative (r_i), and what they do to a product of factors.
    r = np.zeros(3) if scale_error is None else np.asarray(scale_error, dtype=np.float64) / np.abs(s)
    r_det = float(r.sum() + r[0] * r[1] + r[0] * r[2] + r[1] * r[2] + r.prod())
    center = errors.center * np.abs(s)
    if moments.center is not None:
        # The unplaced centre was rounded to the nearest float (half an ulp) and ``c s``
        # rounds once more: both scale with the part's distance from the origin.
        center = center + (np.spacing(np.abs(moments.center)) + _EPS * np.abs(moments.center)) * np.abs(s)
        if scale_error is not None:
            center = center + _UP * (np.abs(moments.center) + errors.center) * np.asarray(scale_error)
    # ``det`` and ``V det`` round (3 roundings of the result), and the factors' errors.
    volume_error = errors.volume * abs(det) * (1.0 + r_det) + _UP * abs(volume) * (r_det + 2 * _EPS)
    central_error = errors.central * np.abs(outer * det)
    if central is not None:
        # ``s sᵀ``, ``det`` and two products round (5 roundings), and the factors' errors.
        r_ij = r[:, None] + r[None, :] + r[:, None] * r[None, :]
        rel = r_det + r_ij + r_det * r_ij
        central_error = central_error * (1.0 + rel) + _UP * np.abs(central) * (rel + 3 * _EPS)
    return MomentErrors(volume_error, center, central_error)


def rotate_moments(moments: Moments, rotation, rotation_error=None) -> Moments:
    """Moments after the rotation ``x -> R x`` about the world origin.

    Parameters
    ----------
    moments : Moments
    rotation : (3, 3) array_like of float
        A proper rotation matrix.
    rotation_error : (3, 3) array_like of float, optional
        Bounds on how far each entry is from the exact rotation it stands for (a composed
        rotation's rounding).
    """
    r = np.asarray(rotation, dtype=np.float64)
    if moments.is_empty:
        return moments
    center, central = r @ moments.center, r @ moments.central @ r.T
    errors = moments.errors
    if errors is not None:
        # Rotating mixes components; bound each by the largest before rotation. The product
        # ``R c`` also rounds (3 products and 2 sums per component, each a relative eps/2 of at
        # most |c|), and the unplaced centre itself was rounded to half an ulp: far from the
        # origin these dominate (a box at 1e8 turned 45°). Likewise ``R C Rᵀ``.
        norm_c = float(np.linalg.norm(moments.center))
        center_error = np.full(3, np.linalg.norm(errors.center) + float(np.linalg.norm(np.spacing(np.abs(
            moments.center)))) + 4 * _EPS * norm_c)
        central_error = np.full((3, 3), np.linalg.norm(errors.central) + 8 * _EPS * float(np.linalg.norm(
            moments.central)))
        if rotation_error is not None:
            # δR (c + δc), and δR C Rᵀ + R C δRᵀ + δR C δRᵀ with |C| and |C| + δC.
            e = np.asarray(rotation_error, dtype=np.float64)
            a, c = np.abs(r), np.abs(moments.center) + errors.center
            big_c = np.abs(moments.central) + errors.central
            center_error = center_error + _UP * (e @ c)
            central_error = central_error + _UP * (e @ big_c @ (a + e).T + a @ big_c @ e.T)
        errors = MomentErrors(errors.volume, center_error, central_error)
    return Moments(moments.volume, center, central, errors)


def translate_moments(moments: Moments, offset, offset_error=None) -> Moments:
    """Moments after the translation ``x -> x + t``; only the centre moves.

    ``offset_error`` (3,), optional: bounds on how far ``t`` is from its exact value (a
    composed translation's rounding)."""
    t = np.asarray(offset, dtype=np.float64).reshape(3)
    if moments.is_empty:
        return moments
    center = moments.center + t
    errors = moments.errors
    if errors is not None:
        # The unplaced centre was rounded to half an ulp of ITS magnitude, and ``c + t`` rounds
        # to half an ulp of the sum's: a part at 1e8 moved back by -1e8 keeps the first, which
        # the final centre's own ulp no longer covers.
        center_error = errors.center + np.spacing(np.abs(moments.center)) + np.spacing(np.abs(center))
        if offset_error is not None:
            # Rounded up: a composed translation's rounding is known exactly, so this bound can
            # be all but reached, and its own additions must not round it below the error.
            center_error = (center_error + np.asarray(offset_error, dtype=np.float64)) * _UP
        errors = MomentErrors(errors.volume, center_error, errors.central)
    return Moments(moments.volume, center, moments.central, errors)


def shape_moments(shape, source: str) -> Moments:
    """A shape's closed-form moments, range-checked (math's ``**`` raises where numpy gives inf).

    Parameters
    ----------
    shape : Shape
    source : str
        What to name in an error.

    Raises
    ------
    RangeError
    """
    try:
        moments = shape.moments()
    except OverflowError:
        raise RangeError(source, "the volume or its moments overflow float64",
                         "measure in a larger unit (e.g. km instead of mm)") from None
    check_range(source, None, moments)
    return moments


def check_range(where: str, before: Moments | None, after: Moments) -> None:
    """Refuse moments that a shape's size or a placement pushed out of float64's range.

    A volume or second moment that was non-zero ``before`` (``before=None`` for a shape, whose
    are never zero) and is zero or subnormal ``after`` underflowed (a subnormal keeps only a
    few bits); an infinite or NaN one overflowed. Either would print a silently wrong number.

    Raises
    ------
    RangeError
    """
    with np.errstate(all="ignore"):
        values = [after.volume] + ([] if after.is_empty else [after.center, after.central])
        if not all(np.isfinite(v).all() for v in values):
            raise RangeError(where, "the volume or its moments overflow float64",
                             "measure in a larger unit (e.g. km instead of mm)")
        # Below float64's normal range (2**-1022) a value keeps only a few bits: as lost as 0.
        tiny = np.finfo(np.float64).tiny
        if before is None:  # a shape
            lost = abs(after.volume) < tiny or after.is_empty or bool(np.any(np.abs(np.diag(after.central)) < tiny))
        else:
            lost = before.volume != 0 and abs(after.volume) < tiny
            if not before.is_empty and not after.is_empty:
                lost = lost or bool(np.any((np.diag(before.central) != 0) & (np.abs(np.diag(after.central)) < tiny)))
    if lost:
        raise RangeError(where, "the volume or its second moments underflow float64 (the part is too small)",
                         "measure in a smaller unit (e.g. mm instead of m)")
