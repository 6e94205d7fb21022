"""Monte Carlo error bounds that hold with few samples inside: Clopper-Pearson for the inside
fraction, Hoeffding for the centre and the second moments (docs/accuracy.md, "Few samples
inside"). ``p3d_cli.measure.montecarlo.Estimate.uncertainty`` uses them below ``MIN_INSIDE`` points.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np

from p3d_cli.geometry.inertia import density_for, inertia_from_second_moments
from p3d_cli.results import Bounds


class Sampled(Protocol):
    """What the bounds read of a run (``p3d_cli.measure.montecarlo.Estimate`` is one); a protocol, so
    that this module does not import the estimator that uses it."""

    @property
    def bounds(self) -> Bounds: ...

    @property
    def samples(self) -> int: ...

    @property
    def mean(self) -> np.ndarray: ...

    @property
    def inside(self) -> float: ...

    @property
    def box_volume(self) -> float: ...

#: 2 Φ(-3) ≈ 0.0027, the Gaussian ±3σ miss rate: conservative bounds hold at 1 - ALPHA.
ALPHA = math.erfc(3.0 / math.sqrt(2.0))

_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))


def _central(m: np.ndarray, box_volume: float) -> np.ndarray:
    """``|B| (m2 - m1 m1ᵀ / m0)`` as a (3, 3) matrix, in normalised coordinates."""
    second = np.empty((3, 3))
    for k, (i, j) in enumerate(_PAIRS):
        second[i, j] = second[j, i] = m[4 + k]
    m1 = m[1:4]
    return box_volume * (second - np.outer(m1, m1) / m[0])


def conservative_errors(est: Sampled, density: float | None = None, mass: float | None = None) -> dict:
    """Error bounds for few inside samples: a third of half-widths that each hold with
    probability at least ``1 - ALPHA``, so ``±3`` of them misses no more often than a Gaussian
    ``±3σ``, whatever the shape (docs/accuracy.md, "Few samples inside").

    Volume and mass: Clopper-Pearson on the inside fraction (``k = 0`` gives ``≈ 6.6 / N``, the
    "rule of three" at this level). Centre: given the count ``k`` the inside points are
    independent and uniform in the solid, with normalised coordinates in [-1, 1], so Hoeffding's
    inequality (1963, thm. 2) bounds their mean's error by ``2 √(ln(2/ALPHA) / 2k)``; the box
    caps it. Inertia: Hoeffding on the 3 first and 6 second means and Clopper-Pearson on the
    mass, each at ``ALPHA / 10`` so that all ten hold together, propagated through
    ``cov = s - a aᵀ`` and ``I = M (tr(D) E - D)``, ``D = H cov H``; capped by the box (a
    coordinate in [-1, 1] has variance at most 1: Popoviciu's inequality).
    """
    k, m, half, box = est.inside, est.mean, 0.5 * est.bounds.size, est.box_volume

    def volume_halfwidth(alpha: float) -> float:
        lo, hi = clopper_pearson(k, est.samples, alpha)
        return box * max(hi - m[0], m[0] - lo)

    volume = box * m[0]
    rho = density_for(volume, density, mass)
    dv = volume_halfwidth(ALPHA)
    out = {"volume": dv / 3, "mass": 0.0 if mass is not None else rho * dv / 3,
           "center_of_mass": None, "inertia": None}
    if not k > 0:
        return out
    hoeffding = lambda alpha: math.sqrt(math.log(2.0 / alpha) / (2.0 * k))  # noqa: E731
    a = m[1:4] / m[0]
    out["center_of_mass"] = half * np.minimum(2.0 * hoeffding(ALPHA), 1.0 + np.abs(a)) / 3
    eye = np.eye(3, dtype=bool)
    t = hoeffding(ALPHA / 10)
    cov = _central(m, box) / volume                  # s - a aᵀ, normalised coordinates
    ea, es = 2.0 * t, np.where(eye, 1.0, 2.0) * t   # ranges: u_i in [-1, 1], u_i² in [0, 1], u_i u_j in [-1, 1]
    dcov = es + ea * (np.abs(a)[:, None] + np.abs(a)[None, :]) + ea * ea
    var = np.diag(cov)
    cap = np.where(eye, np.maximum(var, 1.0 - var)[:, None], np.abs(cov) + 1.0)
    hh = np.outer(half, half)
    d, dd = hh * cov, hh * np.minimum(dcov, cap)
    f = inertia_from_second_moments(d)
    df = np.where(eye, np.trace(dd) - dd, dd)       # I_xx = M (D_yy + D_zz); I_xy = -M D_xy
    total = rho * volume
    dm = 0.0 if mass is not None else rho * volume_halfwidth(ALPHA / 10)
    out["inertia"] = (dm * (np.abs(f) + df) + total * df) / 3
    return out


def clopper_pearson(k: float, n: int, alpha: float = ALPHA) -> tuple[float, float]:
    """Exact bounds ``(lo, hi)`` on a binomial fraction from ``k`` successes in ``n`` trials.

    Each misses with probability at most ``alpha / 2`` (Clopper & Pearson 1934): ``hi`` solves
    ``P(X <= k; n, hi) = alpha/2`` and ``lo`` solves ``P(X >= k; n, lo) = alpha/2``, found by
    bisection on ``log p``. A fractional ``k`` (half-inside points of an open mesh) is rounded
    outward. ``k`` is small here (below ``MIN_INSIDE``), so the binomial sums are short.
    """
    def root(kk: int, level: float) -> float:
        """The p at which ``P(X <= kk; n, p)``, falling in p, equals ``level``."""
        j = np.arange(kk + 1.0)
        log_choose = np.concatenate([[0.0], np.cumsum(np.log((n - j[:-1]) / j[1:]))])   # log C(n, j)
        lo, hi = -700.0, 0.0                     # log p; 60 halvings leave a 1e-15 relative error
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            cdf = np.exp(log_choose + j * mid + (n - j) * math.log1p(-math.exp(mid))).sum()
            lo, hi = (mid, hi) if cdf > level else (lo, mid)
        return math.exp(hi)

    k_lo, k_hi = math.floor(k), math.ceil(k)
    hi = 1.0 if k_hi >= n else root(k_hi, alpha / 2)
    lo = 0.0 if k_lo <= 0 else root(k_lo - 1, 1 - alpha / 2)
    return lo, hi
