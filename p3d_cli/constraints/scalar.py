"""The kinematics of a small scene's step in plain Python floats.

For a scene of a few bodies, a numpy call (~1 µs of overhead on arrays of 3-20 numbers) costs
more than the arithmetic it does: a quaternion update is ~50 float operations, ~2 µs in Python
and ~15 µs as a dozen numpy calls. ``small_step`` therefore keeps a small scene's state as lists
of floats and does everything per constraint here (per body in ``body_kernels``), leaving numpy only the
island-sized linear algebra. The formulas are those of ``rotation``, ``rows`` and the constraint
modules (``ball``, ``hinge``, ``bar``), in the same order of operations where that is cheap, so
results agree with the array code to rounding (~1e-16 relative).

Vectors are tuples or lists of 3 floats, matrices 9 floats row-major, quaternions ``[w, x, y, z]``.
"""

from __future__ import annotations

import math

from p3d_cli.constraints.body_kernels import (carry_spin, carry_spin_diagonal, conjugate, conjugate_diagonal,
                                              nudge, turn)
from p3d_cli.constraints import ball, bar, hinge
from p3d_cli.constraints.rows import bar_met_error

#: The per-body kernels live in ``body_kernels``; these names are kept here for their callers.
__all__ = ["Ball", "Bar", "Hinge", "Joint", "apply", "carry_spin", "carry_spin_diagonal", "conjugate",
           "conjugate_diagonal", "cross", "make_joint", "nudge", "turn"]


def apply(r, v) -> tuple[float, float, float]:
    """``R v`` for a row-major 3×3 ``r``."""
    v0, v1, v2 = v
    return (r[0] * v0 + r[1] * v1 + r[2] * v2, r[3] * v0 + r[4] * v1 + r[5] * v2,
            r[6] * v0 + r[7] * v1 + r[8] * v2)


def cross(a, b) -> tuple[float, float, float]:
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


class Joint:
    """One constraint's constants and its per-configuration evaluation (a subclass per type).

    ``evaluate`` returns the position errors (``rows.RowSet.errors`` for this constraint) and
    keeps what ``entries`` (the variable entries of its rows) needs. A fixed side's attachment
    point (and hinge axis) is computed once: its body never moves.
    """

    __slots__ = ("a", "b", "off_a", "off_b", "free_a", "free_b", "const_a", "const_b", "where", "_state",
                 "axial_a", "axial_b", "_both_axial")
    kind = ""
    rows = 0

    def __init__(self, a, b, off_a, off_b, free_a: bool, free_b: bool, com, rot, where) -> None:
        self.a, self.b, self.off_a, self.off_b = a, b, off_a, off_b
        self.free_a, self.free_b, self.where = free_a, free_b, where
        self.const_a = None if free_a else _point(com, rot, a, off_a)
        self.const_b = None if free_b else _point(com, rot, b, off_b)
        self.axial_a, self.axial_b = _axial(off_a), _axial(off_b)
        # Both sides free with axial offsets (the links of a chain): the indices ``points``
        # needs, unpacked from one attribute (3 column entries of R, the centre's 3 entries).
        self._both_axial = None
        if free_a and free_b and self.axial_a is not None and self.axial_b is not None:
            (ja, oa), (jb, ob) = self.axial_a, self.axial_b
            self._both_axial = (a, 3 * a, ja, ja + 3, ja + 6, oa, b, 3 * b, jb, jb + 3, jb + 6, ob)
        self._state: tuple = ()

    def points(self, com, rot) -> list[float]:
        """``gap = p_b - p_a`` as a list (``rows.RowSet.geometry``), keeping ``(r_a, r_b)``, the
        offsets of the attachment points from the centres of mass (world frame), as ``_state``.

        The gap is a ball joint's errors, so that ``Ball.evaluate`` is this function (one call
        less for the commonest joint: this runs for every constraint 3-6 times a step)."""
        plan = self._both_axial
        if plan is not None:
            # The axial branches below for both sides, without their attribute look-ups and
            # index sums: the same operations in the same order, a third less time.
            ia, ka, a0, a1, a2, oa, ib, kb, b0, b1, b2, ob = plan
            r = rot[ia]
            ra = (r[a0] * oa, r[a1] * oa, r[a2] * oa)
            r = rot[ib]
            rb = (r[b0] * ob, r[b1] * ob, r[b2] * ob)
            self._state = (ra, rb)
            return [com[kb] + rb[0] - (com[ka] + ra[0]), com[kb + 1] + rb[1] - (com[ka + 1] + ra[1]),
                    com[kb + 2] + rb[2] - (com[ka + 2] + ra[2])]
        # _point written out twice: this runs for every constraint 3-6 times a step. An offset
        # along one body axis (a link's end) takes that column of R only: the products with its
        # zero components are exact zeros, so the sums are the same numbers (up to the sign of a
        # zero), in a third of the work.
        if self.const_a is None:
            r, k = rot[self.a], 3 * self.a
            axial = self.axial_a
            if axial is not None:
                j, o = axial
                ra = (r[j] * o, r[j + 3] * o, r[j + 6] * o)
            else:
                o0, o1, o2 = self.off_a
                ra = (r[0] * o0 + r[1] * o1 + r[2] * o2, r[3] * o0 + r[4] * o1 + r[5] * o2,
                      r[6] * o0 + r[7] * o1 + r[8] * o2)
            pa = (com[k] + ra[0], com[k + 1] + ra[1], com[k + 2] + ra[2])
        else:
            ra, pa = self.const_a
        if self.const_b is None:
            r, k = rot[self.b], 3 * self.b
            axial = self.axial_b
            if axial is not None:
                j, o = axial
                rb = (r[j] * o, r[j + 3] * o, r[j + 6] * o)
            else:
                o0, o1, o2 = self.off_b
                rb = (r[0] * o0 + r[1] * o1 + r[2] * o2, r[3] * o0 + r[4] * o1 + r[5] * o2,
                      r[6] * o0 + r[7] * o1 + r[8] * o2)
            pb = (com[k] + rb[0], com[k + 1] + rb[1], com[k + 2] + rb[2])
        else:
            rb, pb = self.const_b
        self._state = (ra, rb)
        return [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]]

    def columns(self) -> list[tuple[int, int]]:
        """(row, column within a side's 6) of one side's ``entries``, in order."""
        return list(SKEW)

    def entries(self) -> list[float]:
        """The entries of its rows that depend on the pose, side a's then side b's (free sides
        only), in the order ``small_step`` scatters them (the ``±E`` entries, and the zero
        diagonal of the cross-product matrices, are constant and written once).
        Ball rows (a hinge's first three): ``[-E, [r_a]ₓ]`` and ``[E, -[r_b]ₓ]``."""
        ra, rb = self._state[0], self._state[1]
        out = [-ra[2], ra[1], ra[2], -ra[0], -ra[1], ra[0]] if self.free_a else []
        if self.free_b:
            out += [rb[2], -rb[1], -rb[2], rb[0], rb[1], -rb[0]]
        return out


#: (row, column) of the off-diagonal entries of a cross-product matrix ``[r]ₓ`` in a side's 6
#: columns of a ball row, in ``Joint.entries``' order.
SKEW = ((0, 4), (0, 5), (1, 3), (1, 5), (2, 3), (2, 4))


def _axial(off):
    """``(j, o)`` when ``off`` is ``o`` times the ``j``-th unit vector (``o`` finite, non-zero), else None."""
    nonzero = [j for j in range(3) if off[j] != 0.0]
    if len(nonzero) == 1 and math.isfinite(off[nonzero[0]]):
        return nonzero[0], off[nonzero[0]]
    return None


def _point(com, rot, i: int, off):
    """``(R off, com + R off)`` of body ``i``."""
    r, k = rot[i], 3 * i
    o0, o1, o2 = off
    v0, v1, v2 = r[0] * o0 + r[1] * o1 + r[2] * o2, r[3] * o0 + r[4] * o1 + r[5] * o2, r[6] * o0 + r[7] * o1 + r[8] * o2
    return (v0, v1, v2), (com[k] + v0, com[k + 1] + v1, com[k + 2] + v2)


class Ball(Joint):
    __slots__ = ()
    kind, rows = "ball", ball.EQUATIONS
    evaluate = Joint.points


class Bar(Joint):
    __slots__ = ("length",)
    kind, rows = "bar", bar.EQUATIONS
    length: float

    def evaluate(self, com, rot) -> list[float]:
        gap = self.points(com, rot)
        ra, rb = self._state
        norm = math.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])
        self._state = (ra, rb, gap, norm)
        return [norm - self.length]

    def columns(self) -> list[tuple[int, int]]:
        return [(0, j) for j in range(6)]

    def entries(self) -> list[float]:
        """``[-d, -(r_a × d)]`` and ``[d, r_b × d]``, ``d`` the unit vector from ``p_a`` to ``p_b``."""
        ra, rb, gap, norm = self._state
        if norm == 0.0:
            raise bar_met_error(self.where)
        d = (gap[0] / norm, gap[1] / norm, gap[2] / norm)
        out: list[float] = []
        if self.free_a:
            ca = cross(ra, d)
            out += [-d[0], -d[1], -d[2], -ca[0], -ca[1], -ca[2]]
        if self.free_b:
            out += [*d, *cross(rb, d)]
        return out


class Hinge(Joint):
    __slots__ = ("axis_a", "axis_b", "z_a", "z_b", "along_a", "along_b")
    kind, rows = "hinge", hinge.EQUATIONS
    axis_a: list
    axis_b: list
    z_a: tuple | None
    z_b: tuple | None
    along_a: tuple | None
    along_b: tuple | None

    def set_axes(self, axis_a, axis_b, rot) -> None:
        self.axis_a, self.axis_b = axis_a, axis_b
        self.z_a = None if self.free_a else apply(rot[self.a], axis_a)
        self.z_b = None if self.free_b else apply(rot[self.b], axis_b)
        # An axis along a body axis (the usual case) is a column of R: see Joint.points.
        self.along_a, self.along_b = _axial(axis_a), _axial(axis_b)

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
        # rows.hinge_frames for one hinge: z the bisector of the world axes (zb flipped when it
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


def make_joint(kind: str, a: int, b: int, off_a, off_b, free_a: bool, free_b: bool, com, rot, where: str,
               axes=None, length: float = 0.0) -> Joint:
    """The ``Ball``, ``Hinge`` (body-frame unit ``axes``) or ``Bar`` (``length``) of a constraint."""
    if kind == "ball":
        return Ball(a, b, off_a, off_b, free_a, free_b, com, rot, where)
    if kind == "hinge":
        hinge = Hinge(a, b, off_a, off_b, free_a, free_b, com, rot, where)
        hinge.set_axes(axes[0], axes[1], rot)
        return hinge
    bar = Bar(a, b, off_a, off_b, free_a, free_b, com, rot, where)
    bar.length = length
    return bar
