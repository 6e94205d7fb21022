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


def scale_moments(moments: Moments, scale) -> Moments:
    """Moments of the solid after the diagonal scale ``x -> (sx x, sy y, sz z)``.

    Parameters
    ----------
    moments : Moments
    scale : (3,) array_like of float
        Scale factors; negative factors mirror the solid (and so negate its signed volume).

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
        return Moments(volume, None, None, _scaled_errors(moments, s, det, outer))
    return Moments(volume, moments.center * s, moments.central * outer * det,
                   _scaled_errors(moments, s, det, outer))


def _scaled_errors(moments, s, det, outer):
    errors = moments.errors
    if errors is None:
        return None
    center = errors.center * np.abs(s)
    if moments.center is not None:
        # The unplaced centre was rounded to the nearest float (half an ulp) and ``c s``
        # rounds once more: both scale with the part's distance from the origin.
        center = center + (np.spacing(np.abs(moments.center)) + _EPS * np.abs(moments.center)) * np.abs(s)
    return MomentErrors(errors.volume * abs(det), center, errors.central * np.abs(outer * det))


def rotate_moments(moments: Moments, rotation) -> Moments:
    """Moments after the rotation ``x -> R x`` about the world origin.

    Parameters
    ----------
    moments : Moments
    rotation : (3, 3) array_like of float
        A proper rotation matrix.
    """
    r = np.asarray(rotation, dtype=np.float64)
    if moments.is_empty:
        return moments
    errors = moments.errors
    if errors is not None:
        # Rotating mixes components; bound each by the largest before rotation. The product
        # ``R c`` also rounds (3 products and 2 sums per component, each a relative eps/2 of at
        # most |c|), and the unplaced centre itself was rounded to half an ulp: far from the
        # origin these dominate (a box at 1e8 turned 45°). Likewise ``R C Rᵀ``.
        norm_c = float(np.linalg.norm(moments.center))
        center = (np.linalg.norm(errors.center) + float(np.linalg.norm(np.spacing(np.abs(moments.center))))
                  + 4 * _EPS * norm_c)
        central = np.linalg.norm(errors.central) + 8 * _EPS * float(np.linalg.norm(moments.central))
        errors = MomentErrors(errors.volume, np.full(3, center), np.full((3, 3), central))
    return Moments(moments.volume, r @ moments.center, r @ moments.central @ r.T, errors)


def translate_moments(moments: Moments, offset) -> Moments:
    """Moments after the translation ``x -> x + t``; only the centre moves."""
    t = np.asarray(offset, dtype=np.float64).reshape(3)
    if moments.is_empty:
        return moments
    center = moments.center + t
    errors = moments.errors
    if errors is not None:
        # The unplaced centre was rounded to half an ulp of ITS magnitude, and ``c + t`` rounds
        # to half an ulp of the sum's: a part at 1e8 moved back by -1e8 keeps the first, which
        # the final centre's own ulp no longer covers.
        errors = MomentErrors(errors.volume, errors.center + np.spacing(np.abs(moments.center))
                              + np.spacing(np.abs(center)), errors.central)
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
    are never zero) and is zero ``after`` underflowed; an infinite or NaN one overflowed. Either
    would print a silently wrong number.

    Raises
    ------
    RangeError
    """
    with np.errstate(all="ignore"):
        values = [after.volume] + ([] if after.is_empty else [after.center, after.central])
        if not all(np.isfinite(v).all() for v in values):
            raise RangeError(where, "the volume or its moments overflow float64",
                             "measure in a larger unit (e.g. km instead of mm)")
        if before is None:  # a shape
            lost = after.volume == 0 or after.is_empty or bool(np.any(np.diag(after.central) == 0))
        else:
            lost = before.volume != 0 and after.volume == 0
            if not before.is_empty and not after.is_empty:
                lost = lost or bool(np.any((np.diag(before.central) != 0) & (np.diag(after.central) == 0)))
    if lost:
        raise RangeError(where, "the volume or its second moments underflow float64 (the part is too small)",
                         "measure in a smaller unit (e.g. mm instead of m)")
