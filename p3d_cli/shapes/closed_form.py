"""Exact canonical constants, as ``fractions.Fraction``, turned into float ``Moments``.

Each shape module states its canonical solid's volume, centre and central second moments
``C = ∫ (x - c)(x - c)ᵀ dV`` exactly (rationals, times π for the round shapes), with the
derivation beside them. ``tests/shapes`` checks the polyhedral ones against the polyhedral
formulas evaluated in rational arithmetic, and the round ones against refined tessellations.
A scaled shape's moments are these constants mapped by ``p3d_cli.geometry.moments.scale_moments``
(the Physics3D note's eq. 4, 5 and 9, exact for any diagonal scale).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.results import Moments


def canonical_moments(volume, center, central, factor: float = 1.0) -> Moments:
    """``Moments`` in float64 from exact constants.

    Parameters
    ----------
    volume : Fraction
    center : 3 Fractions
    central : 3 × 3 Fractions
    factor : float
        Multiplies ``volume`` and ``central`` (π for the sphere and cylinder).
    """
    return Moments(float(volume) * factor, np.array([float(c) for c in center]),
                   np.array([[float(c) for c in row] for row in central]) * factor)
