"""The kinematics of a small scene's step in plain Python floats: what every constraint type's
scalar form (its module's ``SmallJoint``, a ``Joint``) shares.

For a scene of a few bodies, a numpy call (~1 µs of overhead on arrays of 3-20 numbers) costs
more than the arithmetic it does: a quaternion update is ~50 float operations, ~2 µs in Python
and ~15 µs as a dozen numpy calls. ``small_step`` therefore keeps a small scene's state as lists
of floats and does everything per constraint in the joints (per body in ``body_kernels``),
leaving numpy only the island-sized linear algebra. The formulas are those of ``rotation`` and of the constraint type
modules' array forms, in the same order of operations where that is cheap, so results agree
with the array code to rounding (~1e-16 relative).

Vectors are tuples or lists of 3 floats, matrices 9 floats row-major, quaternions ``[w, x, y, z]``.
"""

from __future__ import annotations

import math

from p3d_cli.constraints.body_kernels import (carry_spin, carry_spin_diagonal, conjugate, conjugate_diagonal,
                                              nudge, turn)

#: The per-body kernels live in ``body_kernels``; these names are kept here for their callers.
__all__ = ["Joint", "apply", "axial", "carry_spin", "carry_spin_diagonal", "conjugate", "conjugate_diagonal",
           "cross", "nudge", "turn"]


def apply(r, v) -> tuple[float, float, float]:
    """``R v`` for a row-major 3×3 ``r``."""
    v0, v1, v2 = v
    return (r[0] * v0 + r[1] * v1 + r[2] * v2, r[3] * v0 + r[4] * v1 + r[5] * v2,
            r[6] * v0 + r[7] * v1 + r[8] * v2)


def cross(a, b) -> tuple[float, float, float]:
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


class Joint:
    """One constraint's constants and its per-configuration evaluation (a subclass per type, its
    module's ``SmallJoint``).

    ``configure(spec, rot)`` reads the type's own values of the ``ConstraintSpec``;
    ``evaluate(com, rot)`` returns the position errors (its ``Rows.errors``) and keeps what
    ``entries`` (the variable entries of its rows, at ``columns``) needs. ``constants`` are the
    (row, column) entries that are -1 on side a and +1 on side b whatever the pose. A fixed
    side's attachment point is computed once: its body never moves.

    The defaults are those of rows that keep two points together (a ball's three, a hinge's
    first three): ``[-E, [r_a]ₓ]`` and ``[E, -[r_b]ₓ]``.
    """

    __slots__ = ("a", "b", "off_a", "off_b", "free_a", "free_b", "const_a", "const_b", "where", "_state",
                 "axial_a", "axial_b", "_both_axial")
    rows = 0
    constants: tuple[tuple[int, int], ...] = ((0, 0), (1, 1), (2, 2))
    #: One row whose 6 entries per free side are all variable (a bar's): an island of this
    #: joint alone is solved in floats (``small_islands._Single``).
    single_row = False

    def __init__(self, a, b, off_a, off_b, free_a: bool, free_b: bool, com, rot, where) -> None:
        self.a, self.b, self.off_a, self.off_b = a, b, off_a, off_b
        self.free_a, self.free_b, self.where = free_a, free_b, where
        self.const_a = None if free_a else _point(com, rot, a, off_a)
        self.const_b = None if free_b else _point(com, rot, b, off_b)
        self.axial_a, self.axial_b = axial(off_a), axial(off_b)
        # Both sides free with axial offsets (the links of a chain): the indices ``points``
        # needs, unpacked from one attribute (3 column entries of R, the centre's 3 entries).
        self._both_axial = None
        if free_a and free_b and self.axial_a is not None and self.axial_b is not None:
            (ja, oa), (jb, ob) = self.axial_a, self.axial_b
            self._both_axial = (a, 3 * a, ja, ja + 3, ja + 6, oa, b, 3 * b, jb, jb + 3, jb + 6, ob)
        self._state: tuple = ()

    def configure(self, spec, rot) -> None:
        """Take the type's own values of ``spec`` (a ``ConstraintSpec``); none by default."""

    def sides(self) -> list[tuple[int, bool, tuple | None]]:
        """``(body, free, (j, o) or None)`` of every body-frame vector the joint reads of a body's
        rotation: its attachment offsets (``axial``), and a type's own (a hinge's axes)."""
        return [(self.a, self.free_a, self.axial_a), (self.b, self.free_b, self.axial_b)]

    def points(self, com, rot) -> list[float]:
        """``gap = p_b - p_a`` as a list (``rows.RowSet.geometry``), keeping ``(r_a, r_b)``, the
        offsets of the attachment points from the centres of mass (world frame), as ``_state``.

        The gap is a ball joint's errors, so that ``ball.SmallJoint.evaluate`` is this function (one call
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


def axial(off):
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
