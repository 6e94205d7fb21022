"""Ball joint: two body points stay together (the Physics3D note's eqs. 21-29, signs per
docs/method.md, "Point velocity sign").

Velocity equation (3 rows): ``(v_b + ω_b × r_b) - (v_a + ω_a × r_a) = 0``. Since
``ω × r = -[r]ₓ ω``, the motion-to-equation matrix of a side is ``ME = [E, -[r]ₓ]`` (the note's
eq. 28-29 have ``+[r]ₓ``, the wrong sign). The multiplier ``λ`` is the impulse on body ``b``,
world frame; ``a`` receives ``-λ``.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.constraints import scalar
from p3d_cli.constraints.rotation import skew

#: The keys of its scene entry besides ``type``, ``a`` and ``b`` (docs/solve.md).
KEYS = ("attach_a", "attach_b")
#: Rows per constraint.
EQUATIONS = 3
#: Body-frame vectors its world geometry turns (``hinge.TURNED``): none.
TURNED: tuple = ()


def read(spec: dict, place: str, body_a, body_b, attach_a, attach_b) -> dict:
    """Its own values of a scene entry (``ConstraintSpec.values``): none beyond the attachments."""
    return {}


def jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (3, 6): rows of ``J_a u_a + J_b u_b`` with ``u = (v, ω)``."""
    ja, jb = np.zeros((3, 6)), np.zeros((3, 6))
    jb[:, :3] = _EYE
    jb[:, 3:] = -skew(geo.r_b)
    ja[:, :3] = -_EYE
    ja[:, 3:] = skew(geo.r_a)
    return ja, jb


_EYE = np.eye(3)


def position_error(spec, geo) -> np.ndarray:
    """(3,) ``p_b - p_a``: the gap between the two attachment points."""
    return geo.p_b - geo.p_a


def impulse(geo, lam: np.ndarray) -> dict:
    """The impulse on body ``b`` (world frame)."""
    return {"impulse": lam.copy()}


class Rows:
    """The array form (``rows.RowSet``): the rows of every ball joint of a scene at once.

    Also a hinge's first three rows (``hinge.Rows`` holds one for its hinges).
    """

    def __init__(self, specs, ks: np.ndarray, offsets: np.ndarray) -> None:
        self.ks = ks
        self.rows = offsets[ks][:, None] + np.arange(3)
        self.flat = self.rows.ravel()

    def template(self, ja: np.ndarray, jb: np.ndarray) -> None:
        ja[self.rows, np.arange(3)] = -1.0
        jb[self.rows, np.arange(3)] = 1.0

    def errors(self, geo, g: int, out: np.ndarray) -> None:
        out[self.rows] = geo.gap[self.ks]

    def jacobian(self, geo, g: int, ja: np.ndarray, jb: np.ndarray) -> None:
        # [-E, [r_a]ₓ] and [E, -[r_b]ₓ] (the ±E are the template's).
        ja[self.flat, 3:] = (geo.r_a[self.ks][:, _SKEW_PICK] * _SKEW_SIGN).reshape(-1, 3)
        jb[self.flat, 3:] = (geo.r_b[self.ks][:, _SKEW_PICK] * -_SKEW_SIGN).reshape(-1, 3)


#: ``[r]ₓ`` row-major as ``r[_SKEW_PICK] * _SKEW_SIGN`` (``rotation.skew``).
_SKEW_PICK = np.array([0, 2, 1, 2, 0, 0, 1, 0, 0])
_SKEW_SIGN = np.array([0.0, -1, 1, 1, 0, -1, -1, 1, 0])


class SmallJoint(scalar.Joint):
    """The scalar form (``small_step``): its errors are the gap, its rows ``scalar.Joint``'s."""

    __slots__ = ()
    rows = EQUATIONS
    evaluate = scalar.Joint.points
