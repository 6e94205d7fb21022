"""Zero where the answer is zero: values within their rounding-error bound of 0 print as 0.

The exact method gives an a-priori bound on the rounding error of each quantity
(``PropsResult.uncertainty``; docs/method.md). A value no larger than its bound cannot be told
from zero (a symmetric part's ``Ixy`` of ``9.94e-36``), so the human table and ``--csv`` show
it as 0; ``--json`` keeps every value as computed, with its bound beside it.
"""

from __future__ import annotations

import numpy as np

EPS = float(np.finfo(np.float64).eps)


def snapped(record: dict) -> dict:
    """A copy of a ``props`` record whose values within their rounding bound of zero are 0.

    Only exact results are snapped (Monte Carlo's uncertainties are standard errors, not
    bounds). Quantities derived after the bounded ones get bounds of their own here:

    - principal moments: by Weyl's inequality an eigenvalue of a symmetric ``I + E`` is within
      ``||E||_2 <= ||E||_F`` of ``I``'s (Horn and Johnson, *Matrix Analysis*, 4.3.1);
    - inertia about the origin or the ``--about`` point, ``I + m (|d|² E - d dᵀ)``: the
      first-order propagation of the bounds of ``I``, ``m`` and ``d`` (the centre's), plus
      four roundings of the sum;
    - principal axes: components of a unit vector no larger than ``8 eps`` (its normalisation's
      rounding).
    """
    u = record.get("uncertainty")
    if record.get("method") != "exact" or not u or record.get("center_of_mass") is None:
        return dict(record)
    out = dict(record)
    bounds: dict = {key: u.get(key) for key in ("volume", "mass", "center_of_mass", "inertia")}
    inertia_bound = u.get("inertia")
    if inertia_bound is not None:
        inertia_bound = np.asarray(inertia_bound, dtype=float)
        bounds["principal_moments"] = float(np.linalg.norm(inertia_bound))
        bounds["principal_axes"] = 8 * EPS
        com, com_bound = np.asarray(record["center_of_mass"], float), np.asarray(u["center_of_mass"], float)
        mass, mass_bound = float(record["mass"]), float(u.get("mass") or 0.0)
        inertia = np.asarray(record["inertia"], float)
        bounds["inertia_origin"] = shifted_bound(inertia, inertia_bound, mass, mass_bound, com, com_bound)
        if record.get("about") is not None:
            d = com - np.asarray(record["about"], float)
            bounds["inertia_about"] = shifted_bound(inertia, inertia_bound, mass, mass_bound, d, com_bound)
    for key, bound in bounds.items():
        if bound is not None and out.get(key) is not None:
            out[key] = zeroed(out[key], bound)
    return out


def shifted_bound(inertia, inertia_bound, mass, mass_bound, d, d_bound) -> np.ndarray:
    """A bound on the error of ``I + m (|d|² E - d dᵀ)`` (the parallel-axis shift by ``d``)."""
    a, da = np.abs(d), np.asarray(d_bound, float)
    eye = np.eye(3)
    term = abs(mass) * (float(a @ a) * eye + np.outer(a, a))
    propagated = (inertia_bound + mass_bound * (float(a @ a) * eye + np.outer(a, a))
                  + abs(mass) * (2 * float(a @ da) * eye + np.outer(da, a) + np.outer(a, da)))
    return propagated + 4 * EPS * (np.abs(inertia) + term)


def zeroed(value, bound):
    """``value`` with the entries no larger in magnitude than ``bound`` (broadcast) set to 0."""
    array = np.asarray(value, dtype=float)
    result = np.where(np.abs(array) <= np.asarray(bound, dtype=float), 0.0, array)
    return float(result) if result.ndim == 0 else result
