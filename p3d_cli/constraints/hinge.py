"""Hinge: a ball joint whose bodies may only turn relative to each other about one axis
(the Physics3D note's eqs. 30-38, signs per docs/method.md, "Point velocity sign").

Velocity equations (5 rows): the ball joint's three, and ``(ω_b - ω_a)·x = 0``,
``(ω_b - ω_a)·y = 0`` with ``x``, ``y`` perpendicular to the world hinge axis ``z``.

The axes are lines: ``axis_a`` and ``axis_b`` may point either way along them. ``z`` is the
bisector of the two world axes (``z_b`` flipped when it points away from ``z_a``), so neither side
is privileged; when the joint is assembled both axes agree and ``z`` is simply that axis.
The position error of the axes is ``(z_a × s z_b)·x`` and ``·y`` (``s = ±1`` the same flip):
first order in the misalignment, and zero for parallel and anti-parallel axes alike (docs/method.md, "Hinge").

The multipliers are a linear impulse on ``b`` (3) and an angular impulse on ``b`` perpendicular
to the axis (reported as the world vector ``λ_x x + λ_y y``, which does not depend on the choice
of ``x`` and ``y``); ``a`` receives the negatives.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.constraints import ball, values
from p3d_cli.constraints.rotation import cross

#: The keys of its scene entry besides ``type``, ``a`` and ``b`` (docs/solve.md).
KEYS = ("attach_a", "attach_b", "axis_a", "axis_b")
#: Rows per constraint.
EQUATIONS = 5


def read(spec: dict, place: str, body_a, body_b, attach_a, attach_b) -> dict:
    """Its own values of a scene entry (``ConstraintSpec`` fields): the unit axes in each body's
    frame (a missing one is the other's, carried into its body's frame)."""
    axis_a, axis_b = values.pair(spec, "axis", place, body_a, body_b, point=False)
    return {"axis_a": values.unit_vector(axis_a), "axis_b": values.unit_vector(axis_b)}   # nonzero, finite


def frame(geo) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(x, y, z, s)``: an orthonormal frame with ``z`` the hinge axis, and the flip ``s`` of ``z_b``."""
    s = 1.0 if float(geo.z_a @ geo.z_b) >= 0 else -1.0
    z = geo.z_a + s * geo.z_b
    norm = np.linalg.norm(z)
    # Axes at exactly 90° still bisect; only an exactly opposite pair (impossible after the flip)
    # would leave z undefined.
    z = z / norm if norm > 0 else geo.z_a
    # x: the world axis least aligned with z, made perpendicular (deterministic and well
    # conditioned: |x| >= sqrt(2/3) before normalising).
    seed = np.zeros(3)
    seed[int(np.argmin(np.abs(z)))] = 1.0
    x = seed - (seed @ z) * z
    x /= np.linalg.norm(x)
    y = cross(z, x)
    return x, y, z, s


def jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (5, 6)."""
    x, y, _, _ = frame(geo)
    ja_ball, jb_ball = ball.jacobian(geo)
    angular = np.zeros((2, 6))
    angular[0, 3:], angular[1, 3:] = x, y
    return np.vstack([ja_ball, -angular]), np.vstack([jb_ball, angular])


def position_error(spec, geo) -> np.ndarray:
    """(5,): the attachment gap, then the axis misalignment ``(z_a × s z_b)`` along ``x`` and ``y``."""
    x, y, _, s = frame(geo)
    tilt = cross(geo.z_a, s * geo.z_b)
    return np.concatenate([geo.p_b - geo.p_a, [tilt @ x, tilt @ y]])


def impulse(geo, lam: np.ndarray) -> dict:
    """Linear and angular impulse on body ``b`` (world frame)."""
    x, y, _, _ = frame(geo)
    return {"impulse": lam[:3].copy(), "angular_impulse": lam[3] * x + lam[4] * y}
