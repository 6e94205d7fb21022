"""Pure functions on ``Moments``: placing a solid (scale, rotate, translate).

Central second moments ``C = ∫ (x - c)(x - c)ᵀ dV`` make these exact and stable:
a diagonal scale ``S`` maps ``C`` to ``det(S) · S C S`` (the Physics3D note's eq. 8-9, written
for the convention-free second moments), a rotation ``R`` maps it to ``R C Rᵀ``, and a
translation leaves it unchanged; only the centre moves.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.results import MomentErrors, Moments


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
        return Moments(volume, None, None, _scaled_errors(moments.errors, s, det, outer))
    return Moments(volume, moments.center * s, moments.central * outer * det,
                   _scaled_errors(moments.errors, s, det, outer))


def _scaled_errors(errors, s, det, outer):
    if errors is None:
        return None
    return MomentErrors(errors.volume * abs(det), errors.center * np.abs(s),
                        errors.central * np.abs(outer * det))


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
        # Rotating mixes components; bound each by the largest before rotation.
        errors = MomentErrors(errors.volume, np.full(3, np.linalg.norm(errors.center)),
                              np.full((3, 3), np.linalg.norm(errors.central)))
    return Moments(moments.volume, r @ moments.center, r @ moments.central @ r.T, errors)


def translate_moments(moments: Moments, offset) -> Moments:
    """Moments after the translation ``x -> x + t``; only the centre moves."""
    t = np.asarray(offset, dtype=np.float64).reshape(3)
    if moments.is_empty:
        return moments
    return Moments(moments.volume, moments.center + t, moments.central, moments.errors)
