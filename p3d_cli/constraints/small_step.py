"""RATTLE steps of a small scene: state in Python floats, each island's system in numpy.

``World`` evaluates every constraint of one kind in a few numpy calls whatever their number,
which is what a large scene needs; but a scene of a few bodies then pays ~1-2 µs of call
overhead for arrays of 3-20 numbers, about 150 calls a step. Here the per-body and
per-constraint work (drift, quaternions, the constraints' errors and the variable entries of
their rows) is plain float arithmetic (each type's ``SmallJoint`` on ``scalar.Joint``, and
``body_kernels``), and numpy does only what grows with the square of an island's rows
(``small_islands``): its dense system ``J W Jᵀ``, factorised once per step, and the products
with it. The step is the one of ``simulation``
(docs/solve.md, "Stepping"), with the same position-correction iterates: some sums are taken
in another order, and a few formulas are cheaper ones equal to rounding (the correction's
unrefined gain, its small turns by series, bodies of revolution's inertia along their axis),
so trajectories agree to rounding.

Rounding matters in one way: a step whose last correction error lands within a few units in
the last place of the ``1e-12`` tolerance may take one correction more or less than the old
code did (a ~1e-12 difference in positions, a few 1e-12 in velocities once credited ``/ dt``
and projected); the recorded chain has two such steps (docs/solve.md, "Stepping").

Used for scenes whose islands are all dense and small (``fits``); the cost per step still grows
linearly with the number of bodies and constraints, and larger scenes take ``World``'s path.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints.body_kernels import (axis_of_revolution, carry_spin, carry_spin_axial, carry_spin_diagonal,
                                              conjugate, conjugate_axial, conjugate_diagonal, nudge, turn)
from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.constraints.small_islands import _Island, _Single
from p3d_cli.constraints.solver import ImpulseSolution

#: Scenes with at most this many rows, and this many free bodies, take this path.
SMALL_ROWS = 60
SMALL_BODIES = 12


def fits(world) -> bool:
    """Whether ``world``'s scene is small and all its islands are solved densely."""
    return (world.plan.m <= SMALL_ROWS and len(world.moving) <= SMALL_BODIES
            and all(path == "dense" for path, _, _ in world.plan.order))


class SmallStep:
    """The state of a small ``World`` as floats, and its steps (``simulation`` drives them)."""

    def __init__(self, world) -> None:
        rs = world.rowset
        self.n, self.m, self.offsets = len(world.mass), rs.m, rs.offsets
        self.moving = world.moving.tolist()
        self.inv_mass = world.inv_mass.tolist()
        self.inertia = world.inertia_body.reshape(-1, 9).tolist()
        self.inv_inertia_body = world.inv_inertia_body.reshape(-1, 9).tolist()
        # Principal-axis bodies (most: shapes, diagonal inertias) take the diagonal forms, and of
        # those the bodies of revolution (two equal moments) the axial ones.
        self.diagonal: list = [None] * self.n
        self.axial: list = [None] * self.n
        for i, (m, e) in enumerate(zip(self.inertia, self.inv_inertia_body)):
            if not any(m[j] or e[j] for j in (1, 2, 3, 5, 6, 7)):
                self.diagonal[i] = ((m[0], m[4], m[8]), (e[0], e[4], e[8]))
                self.axial[i] = axis_of_revolution(*self.diagonal[i])
        self.com, self.vel = world.com.ravel().tolist(), world.vel.ravel().tolist()
        self.omega = world.omega.ravel().tolist()
        self.quat = [tuple(q) for q in world.quat.tolist()]
        self.rot = world.rot.reshape(-1, 9).tolist()
        active = world.active.tolist()
        joints = []
        for k, spec in enumerate(world.scene.constraints):
            a, b = int(rs.a[k]), int(rs.b[k])
            joints.append(make_joint(spec, a, b, rs.off_a[k].tolist(), rs.off_b[k].tolist(), active[a], active[b],
                                     self.com, self.rot))
        self.islands = [(_Single if len(isl.constraints) == 1 and joints[isl.constraints[0]].single_row else _Island)
                        (isl, joints, rs.offsets, self.inv_mass) for isl in world.islands]
        self.lam: list = [np.zeros(island.m) for island in self.islands]   # minus the last multipliers
        # Moving bodies in no island (no joint to a free body): kicked on their own.
        joined = {i for island in self.islands for i in island.bodies}
        self.loose = [i for i in self.moving if i not in joined]
        for island in self.islands:
            island.errors(self.com, self.rot)
        inv_inertia = self._inv_inertia()
        self.factors = [island.factorise(inv_inertia) for island in self.islands]
        self.column = _axis_columns(self.n, self.axial, joints)
        for i, j in enumerate(self.column):
            if j is not None:
                # Only this column is kept up to date from now on: nan in the others makes a
                # read of them (a bug) show, as a non-finite result, instead of a stale number.
                self.rot[i] = [self.rot[i][c] if c % 3 == j else math.nan for c in range(9)]

    def _inv_inertia(self) -> list:
        """World inverse inertia ``R I⁻¹ Rᵀ`` of every body (9 floats; None for bodies not moving)."""
        out: list = [None] * self.n
        for i in self.moving:
            axial, diagonal = self.axial[i], self.diagonal[i]
            if axial is not None:
                out[i] = conjugate_axial(self.rot[i][axial[0]::3], axial)
            elif diagonal is not None:
                out[i] = conjugate_diagonal(self.rot[i], diagonal[1])
            else:
                out[i] = conjugate(self.rot[i], self.inv_inertia_body[i])
        return out

    # -- one step ---------------------------------------------------------------------------------
    def drift(self, dt: float, half_kick) -> None:
        """The step's first half kick, then ``World.drift``: centres by ``v dt``, orientations by
        ``exp(ω dt)``, keeping ``I_world ω``. (One loop for the two, in the same order of
        operations as two: each body's velocity is kicked before it moves the body.)"""
        com, vel, omega, rot, quat = self.com, self.vel, self.omega, self.rot, self.quat
        diagonal, axial, column = self.diagonal, self.axial, self.column
        g0, g1, g2 = half_kick
        for i in self.moving:
            r, k = rot[i], 3 * i
            w0, w1, w2 = w = (omega[k], omega[k + 1], omega[k + 2])
            vel[k] += g0
            vel[k + 1] += g1
            vel[k + 2] += g2
            com[k] += vel[k] * dt
            com[k + 1] += vel[k + 1] * dt
            com[k + 2] += vel[k + 2] * dt
            a, d, j = axial[i], diagonal[i], column[i]
            if j is not None:
                # A body of revolution read along its axis only: that column of R, turned.
                axis = r[j::3]
                quat[i], turned = turn(quat[i], w0 * dt, w1 * dt, w2 * dt, j)
                r[j], r[j + 3], r[j + 6] = turned
                omega[k], omega[k + 1], omega[k + 2] = carry_spin_axial(axis, turned, a, w)
                continue
            quat[i], turned = turn(quat[i], w0 * dt, w1 * dt, w2 * dt)
            rot[i] = turned
            if a is not None:
                spin = carry_spin_axial(r[a[0]::3], turned[a[0]::3], a, w)
            elif d is not None:
                spin = carry_spin_diagonal(r, turned, d[0], d[1], w)
            else:
                spin = carry_spin(r, turned, self.inertia[i], self.inv_inertia_body[i], w)
            omega[k], omega[k + 1], omega[k + 2] = spin

    def correct(self, tolerance: float, dt: float, iterations: int = 8) -> float:
        """``World.correct_positions`` along the frozen system of the step's start, crediting
        the displacement to the velocities (``/ dt``); returns the largest remaining error."""
        com, rot, quat, islands, factors = self.com, self.rot, self.quat, self.islands, self.factors
        column = self.column
        # Minus each island's motion so far: an array (or a _Single's tuple), summed in the order
        # the per-body totals were, so the same numbers.
        moved: list = [None] * len(islands)
        for iteration in range(iterations + 1):
            errors = [island.errors(com, rot) for island in islands]
            worst = 0.0
            for part in errors:
                worst = max(worst, max(part), -min(part))
            if worst <= tolerance or iteration == iterations:
                break
            for n, island in enumerate(islands):
                change = factors[n].correction(errors[n])          # minus the motion
                total = moved[n]
                if isinstance(change, tuple):
                    moved[n] = change if total is None else tuple([t + c for t, c in zip(total, change)])
                    values = change
                else:
                    moved[n] = change if total is None else total + change
                    values = change.tolist()
                chunks = iter(values)
                for i, d0, d1, d2, d3, d4, d5 in zip(island.bodies, *[chunks] * 6):
                    k = 3 * i
                    com[k] -= d0
                    com[k + 1] -= d1
                    com[k + 2] -= d2
                    if d3 or d4 or d5:
                        # Rows through the centre of mass only (a bob on a bar) turn nothing.
                        j = column[i]
                        if j is None:
                            quat[i], rot[i] = nudge(quat[i], d3, d4, d5)
                        else:
                            r = rot[i]
                            quat[i], (r[j], r[j + 3], r[j + 6]) = nudge(quat[i], d3, d4, d5, j)
        vel, omega = self.vel, self.omega
        for n, island in enumerate(islands):
            total = moved[n]
            if total is None:
                continue
            chunks = iter(total if isinstance(total, tuple) else total.tolist())
            # v + (-s)/dt is v - s/dt exactly: the credit of World.correct_positions.
            for i, d0, d1, d2, d3, d4, d5 in zip(island.bodies, *[chunks] * 6):
                k = 3 * i
                vel[k] -= d0 / dt
                vel[k + 1] -= d1 / dt
                vel[k + 2] -= d2 / dt
                omega[k] -= d3 / dt
                omega[k + 1] -= d4 / dt
                omega[k + 2] -= d5 / dt
        return worst

    def solve_velocities(self, half_kick) -> None:
        """The step's second half kick, then ``World.solve_velocities`` at the configuration of
        the last ``correct``; its factorisation is kept as the next step's frozen system. (An
        island body's kick is added as its velocities are gathered: the same numbers.)"""
        inv_inertia = self._inv_inertia()
        vel, omega = self.vel, self.omega
        g0, g1, g2 = half_kick
        for i in self.loose:
            vel[3 * i] += g0
            vel[3 * i + 1] += g1
            vel[3 * i + 2] += g2
        self.factors = []
        for n, island in enumerate(self.islands):
            factor = island.factorise(inv_inertia)
            self.factors.append(factor)
            u: list[float] = []
            for i in island.bodies:
                k = 3 * i
                v0, v1, v2 = vel[k] + g0, vel[k + 1] + g1, vel[k + 2] + g2
                vel[k], vel[k + 1], vel[k + 2] = v0, v1, v2
                u += (v0, v1, v2, omega[k], omega[k + 1], omega[k + 2])
            lam, change = factor.velocity(u)             # minus the multipliers and the motion
            self.lam[n] = lam
            chunks = iter(change)
            for i, d0, d1, d2, d3, d4, d5 in zip(island.bodies, *[chunks] * 6):
                k = 3 * i
                vel[k] -= d0
                vel[k + 1] -= d1
                vel[k + 2] -= d2
                omega[k] -= d3
                omega[k + 1] -= d4
                omega[k + 2] -= d5

    def finite(self) -> bool:
        """One scalar test that the state is finite (``simulation._check_state``'s first test)."""
        return math.isfinite(sum(self.com) + sum(map(sum, self.quat)) + sum(self.vel) + sum(self.omega))

    # -- exchange with World ----------------------------------------------------------------------
    def store(self, world) -> None:
        """Write the state into ``world``'s arrays (before reporting, or to check it)."""
        n = self.n
        world.com[:] = np.array(self.com).reshape(n, 3)
        world.quat[:] = np.array(self.quat).reshape(n, 4)
        world.vel[:] = np.array(self.vel).reshape(n, 3)
        world.omega[:] = np.array(self.omega).reshape(n, 3)
        world._moved()

    def solution(self) -> ImpulseSolution:
        """The last velocity solve's multipliers, rank and equations, as ``World``'s would be."""
        ranks = tuple((f.rank, island.m) for f, island in zip(self.factors, self.islands))
        lam = np.zeros(self.m)
        for island, part in zip(self.islands, self.lam):
            lam[island.rows] = -part
        return ImpulseSolution(lam, self.offsets, sum(r for r, _ in ranks), sum(e for _, e in ranks),
                               ranks)


def make_joint(spec, a: int, b: int, off_a, off_b, free_a: bool, free_b: bool, com, rot):
    """The scalar form (its type module's ``SmallJoint``) of constraint ``spec`` between bodies
    ``a`` and ``b``, with attachment offsets ``off_a``, ``off_b`` from their centres (body frames)."""
    joint = CONSTRAINT_TYPES[spec.type].SmallJoint(a, b, off_a, off_b, free_a, free_b, com, rot, spec.where)
    joint.configure(spec, rot)
    return joint


def _axis_columns(n: int, axial, joints) -> list:
    """For each body, the column ``j`` of its rotation matrix that is all the step reads of it
    (its inertia's axis of revolution, and every joint on it attached on, and hinged about,
    that body axis: a chain's link, a rod), or None (the whole matrix is kept)."""
    read: list = [set() for _ in range(n)]
    for joint in joints:
        for body, free, along in joint.sides():
            if free:
                read[body].add(None if along is None else along[0])
    out: list = [None] * n
    for i, a in enumerate(axial):
        if a is not None and read[i] == {a[0]}:
            out[i] = a[0]
    return out
