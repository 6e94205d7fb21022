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

import math

import numpy as np

from p3d_cli.constraints import ball, scalar, values
from p3d_cli.constraints.rotation import cross, cross_rows

#: The keys of its scene entry besides ``type``, ``a`` and ``b`` (docs/solve.md).
KEYS = ("attach_a", "attach_b", "axis_a", "axis_b")
#: Rows per constraint.
EQUATIONS = 5
#: Its body-frame vectors (value name, side) that its world geometry turns, in this order:
#: ``JointGeometry.turned`` and ``rows.Geometry.turned`` hold them as ``(z_a, z_b)``.
TURNED = (("axis_a", "a"), ("axis_b", "b"))


def read(spec: dict, place: str, body_a, body_b, attach_a, attach_b) -> dict:
    """Its own values of a scene entry (``ConstraintSpec.values``): the unit axes in each body's
    frame (a missing one is the other's, carried into its body's frame)."""
    axis_a, axis_b = values.pair(spec, "axis", place, body_a, body_b, point=False)
    return {"axis_a": values.unit_vector(axis_a), "axis_b": values.unit_vector(axis_b)}   # nonzero, finite


def frame(geo) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(x, y, z, s)``: an orthonormal frame with ``z`` the hinge axis, and the flip ``s`` of ``z_b``."""
    z_a, z_b = geo.turned
    s = 1.0 if float(z_a @ z_b) >= 0 else -1.0
    z = z_a + s * z_b
    norm = np.linalg.norm(z)
    # Axes at exactly 90° still bisect; only an exactly opposite pair (impossible after the flip)
    # would leave z undefined.
    z = z / norm if norm > 0 else z_a
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
    z_a, z_b = geo.turned
    tilt = cross(z_a, s * z_b)
    return np.concatenate([geo.p_b - geo.p_a, [tilt @ x, tilt @ y]])


def impulse(geo, lam: np.ndarray) -> dict:
    """Linear and angular impulse on body ``b`` (world frame)."""
    x, y, _, _ = frame(geo)
    return {"impulse": lam[:3].copy(), "angular_impulse": lam[3] * x + lam[4] * y}


class Rows:
    """The array form (``rows.RowSet``): the rows of every hinge of a scene at once, its axes
    (``TURNED``) turned into the world frame with the attachment offsets."""

    def __init__(self, specs, ks: np.ndarray, offsets: np.ndarray) -> None:
        self.ball = ball.Rows(specs, ks, offsets)       # the first three rows
        self.axis_rows = offsets[ks][:, None] + np.array([3, 4])

    def template(self, ja: np.ndarray, jb: np.ndarray) -> None:
        self.ball.template(ja, jb)

    def frames(self, geo, g: int):
        """``frames`` of the world axes, computed once per geometry (errors and rows need them)."""
        memo = geo.memo[g]
        if "frames" not in memo:
            memo["frames"] = frames(*geo.turned[g])
        return memo["frames"]

    def errors(self, geo, g: int, out: np.ndarray) -> None:
        self.ball.errors(geo, g, out)
        z_a, z_b = geo.turned[g]
        x, y, _, s = self.frames(geo, g)
        tilt = cross_rows(z_a, s[:, None] * z_b)
        out[self.axis_rows[:, 0]] = (tilt * x).sum(axis=1)
        out[self.axis_rows[:, 1]] = (tilt * y).sum(axis=1)

    def jacobian(self, geo, g: int, ja: np.ndarray, jb: np.ndarray) -> None:
        self.ball.jacobian(geo, g, ja, jb)
        x, y, _, _ = self.frames(geo, g)
        ja[self.axis_rows[:, 0], 3:], jb[self.axis_rows[:, 0], 3:] = -x, x
        ja[self.axis_rows[:, 1], 3:], jb[self.axis_rows[:, 1], 3:] = -y, y


def frames(z_a: np.ndarray, z_b: np.ndarray):
    """``(x, y, z, s)`` of ``frame`` for (h, 3) axis pairs: ``z`` the bisector of the axes
    (``z_b`` flipped by ``s`` when it points away), ``x`` the world axis least aligned with
    ``z`` made perpendicular, ``y = z × x``."""
    s = np.where((z_a * z_b).sum(axis=1) >= 0, 1.0, -1.0)
    z = z_a + s[:, None] * z_b
    # Unit axes with z_a · s z_b >= 0 give |z|² = 2 + 2|z_a · z_b| >= 2: never zero.
    z /= np.sqrt((z * z).sum(axis=1))[:, None]
    pick = np.argmin(np.abs(z), axis=1)
    # x = e_pick - z_pick z, the seed axis made perpendicular (as frame computes it).
    x = _EYE[pick] - z.ravel()[3 * np.arange(len(z)) + pick][:, None] * z
    x /= np.sqrt((x * x).sum(axis=1))[:, None]
    return x, cross_rows(z, x), z, s


_EYE = np.eye(3)


class SmallJoint(scalar.Joint):
    """The scalar form (``small_step``): the ball rows, then the axis rows."""

    __slots__ = ("axis_a", "axis_b", "z_a", "z_b", "along_a", "along_b")
    rows = EQUATIONS
    axis_a: list
    axis_b: list
    z_a: tuple | None
    z_b: tuple | None
    along_a: tuple | None
    along_b: tuple | None

    def configure(self, spec, rot) -> None:
        """The body-frame unit axes; a fixed side's world axis is computed once."""
        axis_a = np.asarray(spec.values["axis_a"], dtype=np.float64).tolist()
        axis_b = np.asarray(spec.values["axis_b"], dtype=np.float64).tolist()
        self.axis_a, self.axis_b = axis_a, axis_b
        self.z_a = None if self.free_a else scalar.apply(rot[self.a], axis_a)
        self.z_b = None if self.free_b else scalar.apply(rot[self.b], axis_b)
        # An axis along a body axis (the usual case) is a column of R: see Joint.points.
        self.along_a, self.along_b = scalar.axial(axis_a), scalar.axial(axis_b)

    def sides(self) -> list[tuple[int, bool, tuple | None]]:
        """The attachment offsets', and the hinge's axis on each side."""
        return super().sides() + [(self.a, self.free_a, self.along_a), (self.b, self.free_b, self.along_b)]

    def _axes(self, rot):
        """World axes ``(z_a, z_b)`` (``apply`` written out: this runs 3-6 times a step)."""
        za = self.z_a
        if za is None:
            r = rot[self.a]
            if self.along_a is not None:
                j, o = self.along_a
                za = (r[j] * o, r[j + 3] * o, r[j + 6] * o)
            else:
                o0, o1, o2 = self.axis_a
                za = (r[0] * o0 + r[1] * o1 + r[2] * o2, r[3] * o0 + r[4] * o1 + r[5] * o2,
                      r[6] * o0 + r[7] * o1 + r[8] * o2)
        zb = self.z_b
        if zb is None:
            r = rot[self.b]
            if self.along_b is not None:
                j, o = self.along_b
                zb = (r[j] * o, r[j + 3] * o, r[j + 6] * o)
            else:
                o0, o1, o2 = self.axis_b
                zb = (r[0] * o0 + r[1] * o1 + r[2] * o2, r[3] * o0 + r[4] * o1 + r[5] * o2,
                      r[6] * o0 + r[7] * o1 + r[8] * o2)
        return za, zb

    def evaluate(self, com, rot) -> list[float]:
        g0, g1, g2 = self.points(com, rot)
        ra, rb = self._state
        (a0, a1, a2), (b0, b1, b2) = self._axes(rot)
        # ``frames`` for one hinge: z the bisector of the world axes (zb flipped when it
        # points away; multiplying by s = 1 is exact, so it is skipped), x the world axis least
        # aligned with z (the first on a tie, as numpy.argmin) made perpendicular, y = z × x.
        if a0 * b0 + a1 * b1 + a2 * b2 < 0:
            b0, b1, b2 = -b0, -b1, -b2
        z0, z1, z2 = a0 + b0, a1 + b1, a2 + b2
        norm = math.sqrt(z0 * z0 + z1 * z1 + z2 * z2)
        z0, z1, z2 = z0 / norm, z1 / norm, z2 / norm
        m0, m1, m2 = abs(z0), abs(z1), abs(z2)
        if m0 <= m1 and m0 <= m2:
            x0, x1, x2 = 1.0 - z0 * z0, -(z0 * z1), -(z0 * z2)
        elif m1 <= m2:
            x0, x1, x2 = -(z1 * z0), 1.0 - z1 * z1, -(z1 * z2)
        else:
            x0, x1, x2 = -(z2 * z0), -(z2 * z1), 1.0 - z2 * z2
        norm = math.sqrt(x0 * x0 + x1 * x1 + x2 * x2)
        x0, x1, x2 = x0 / norm, x1 / norm, x2 / norm
        y0, y1, y2 = z1 * x2 - z2 * x1, z2 * x0 - z0 * x2, z0 * x1 - z1 * x0
        # tilt = z_a × s z_b, along x and y.
        t0, t1, t2 = a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0
        self._state = (ra, rb, (x0, x1, x2), (y0, y1, y2))
        return [g0, g1, g2, t0 * x0 + t1 * x1 + t2 * x2, t0 * y0 + t1 * y1 + t2 * y2]

    def columns(self) -> list[tuple[int, int]]:
        return super().columns() + [(3 + i, 3 + j) for i in range(2) for j in range(3)]

    def entries(self) -> list[float]:
        """The ball rows, then the axis rows ``[0, -x], [0, -y]`` and ``[0, x], [0, y]``."""
        ra, rb, x, y = self._state
        out = [-ra[2], ra[1], ra[2], -ra[0], -ra[1], ra[0],
               -x[0], -x[1], -x[2], -y[0], -y[1], -y[2]] if self.free_a else []
        if self.free_b:
            out += [rb[2], -rb[1], -rb[2], rb[0], rb[1], -rb[0], *x, *y]
        return out
