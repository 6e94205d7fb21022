"""An exact oracle: mass properties of a triangle mesh in rational arithmetic.

Every float64 is a dyadic rational, so all coordinates are written as integers over one
common power of two and the tetrahedron sums are evaluated in Python's unbounded integers
(numpy object arrays, so that 100k triangles take about a second). Only the final divisions
make ``fractions.Fraction`` values. This is independent of p3d's float code: it sums about the
world origin, in exact arithmetic, with the textbook simplex integrals.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np


@dataclass(frozen=True)
class ExactMoments:
    volume: Fraction
    center: tuple[Fraction, Fraction, Fraction]
    central: tuple[tuple[Fraction, ...], ...]      # ∫ (x-c)(x-c)ᵀ dV

    def inertia(self) -> np.ndarray:
        """Positive inertia tensor (unit density), rounded once to float64."""
        c = self.central
        trace = c[0][0] + c[1][1] + c[2][2]
        return np.array([[float((trace if i == j else 0) - c[i][j]) for j in range(3)] for i in range(3)])

    def center_float(self) -> np.ndarray:
        return np.array([float(x) for x in self.center])


def _integers(values: np.ndarray) -> tuple[np.ndarray, int]:
    """Exact integers ``k`` and exponent ``e`` with ``values == k * 2**-e``."""
    flat = np.asarray(values, dtype=np.float64).reshape(-1)
    ratios = [x.as_integer_ratio() for x in flat.tolist()]
    shift = max(d.bit_length() - 1 for _, d in ratios)
    ints = np.array([n << (shift - (d.bit_length() - 1)) for n, d in ratios], dtype=object)
    return ints.reshape(np.shape(values)), shift


def exact_moments(triangles: np.ndarray) -> ExactMoments:
    """Exact volume, centre and central second moments of the solid bounded by ``triangles``.

    Parameters
    ----------
    triangles : (n, 3, 3) float (float32 values are widened exactly)
    """
    k, e = _integers(np.asarray(triangles, dtype=np.float64))
    a, b, c = k[:, 0], k[:, 1], k[:, 2]
    det = (a[:, 0] * (b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1])
           + a[:, 1] * (b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2])
           + a[:, 2] * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0]))
    s = a + b + c
    six_v = int(det.sum())
    first = [int((det * s[:, i]).sum()) for i in range(3)]
    second = [[int((det * (a[:, i] * a[:, j] + b[:, i] * b[:, j] + c[:, i] * c[:, j]
                           + s[:, i] * s[:, j])).sum()) for j in range(3)] for i in range(3)]
    volume = Fraction(six_v, 6 << (3 * e))
    if volume == 0:
        raise ZeroDivisionError("the mesh encloses no volume")
    moment1 = [Fraction(f, 24 << (4 * e)) for f in first]
    center = tuple(m / volume for m in moment1)
    moment2 = [[Fraction(second[i][j], 120 << (5 * e)) for j in range(3)] for i in range(3)]
    central = tuple(tuple(moment2[i][j] - volume * center[i] * center[j] for j in range(3))
                    for i in range(3))
    return ExactMoments(volume, center, central)
