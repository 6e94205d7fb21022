"""RATTLE steps of a small scene: state in Python floats, each island's system in numpy.

``World`` evaluates every constraint of one kind in a few numpy calls whatever their number,
which is what a large scene needs; but a scene of a few bodies then pays ~1-2 µs of call
overhead for arrays of 3-20 numbers, about 150 calls a step. Here the per-body and
per-constraint work (drift, quaternions, the constraints' errors and the variable entries of
their rows) is plain float arithmetic (``scalar``), and numpy does only what grows with the
square of an island's rows: its dense system ``J W Jᵀ``, factorised once per step, and the
products with it. The step is the one of ``simulation`` (docs/solve.md, "Stepping"), operation
for operation; only the order of some sums differs, so trajectories agree to rounding.

Used for scenes whose islands are all dense and small (``fits``); the cost per step still grows
linearly with the number of bodies and constraints, and larger scenes take ``World``'s path.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints.scalar import (carry_spin, carry_spin_diagonal, conjugate, conjugate_diagonal, make_joint,
                                        turn)
from p3d_cli.constraints.solver import RANK_RTOL, ImpulseSolution

try:
    # numpy.linalg's own LAPACK gufuncs, without the public wrappers' checks and error-state
    # set-up (~4 µs a call, a tenth of a small scene's step); results are identical.
    from numpy.linalg import _umath_linalg as _gufuncs
except ImportError:  # pragma: no cover - a numpy that moved them: the public functions
    _gufuncs = None


def _private_gufuncs_agree() -> bool:
    """Whether the private gufuncs take these calls and give the public functions' numbers on
    a small known matrix (a private API may change under a new numpy: then they are not used)."""
    probe = np.array([[4.0, 1.0, 0.5], [1.0, 3.0, 0.25], [0.5, 0.25, 2.0]])
    try:
        inverse = _gufuncs.inv(probe, signature="d->d")
        values, vectors = _gufuncs.eigh_lo(probe, signature="d->dd")
    except Exception:  # noqa: BLE001 - any failure means: use the public functions
        return False
    public_values, public_vectors = np.linalg.eigh(probe)
    return (np.array_equal(inverse, np.linalg.inv(probe)) and np.array_equal(values, public_values)
            and np.array_equal(np.abs(vectors), np.abs(public_vectors)))


if _gufuncs is not None and not _private_gufuncs_agree():  # pragma: no cover
    _gufuncs = None


def _inverse(a: np.ndarray) -> np.ndarray:
    """``inv(a)``; a singular ``a`` gives non-finite entries (or ``LinAlgError``)."""
    if _gufuncs is None:  # pragma: no cover
        return np.linalg.inv(a)
    return _gufuncs.inv(a, signature="d->d")


def _eigh(a: np.ndarray):
    """``numpy.linalg.eigh(a)``, which is called when the fast call's result is not finite so
    that it raises as it would have."""
    if _gufuncs is not None:
        values, vectors = _gufuncs.eigh_lo(a, signature="d->dd")
        if math.isfinite(float(values.sum())):
            return values, vectors
    return np.linalg.eigh(a)


#: Scenes with at most this many rows, and this many free bodies, take this path.
SMALL_ROWS = 60
SMALL_BODIES = 12


def fits(world) -> bool:
    """Whether ``world``'s scene is small and all its islands are solved densely."""
    return (world.plan.m <= SMALL_ROWS and len(world.moving) <= SMALL_BODIES
            and all(path == "dense" for path, _, _ in world.plan.order))


class _Factor:
    """One island's factorised system: ``K`` the pseudo-inverse of ``A = J W Jᵀ``, and ``W Jᵀ``."""

    __slots__ = ("jac", "wjt", "system", "pinv", "rank")

    def __init__(self, jac, wjt, system, pinv, rank) -> None:
        self.jac, self.wjt, self.system, self.pinv, self.rank = jac, wjt, system, pinv, rank

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Minimum-norm ``λ`` of ``A λ = b`` with one step of iterative refinement, which recovers
        the digits the factorisation's rounding loses on an ill-conditioned island (so an
        explicit (pseudo-)inverse is as accurate here as applying the factors)."""
        dot = self.pinv.dot
        lam = dot(b)
        return lam + dot(b - self.system.dot(lam))

    # Both right-hand sides carry a minus sign (``-C``, ``-J u``); every operation of the solve is
    # linear and rounds symmetrically, so solving for ``+C`` and subtracting the result is exact
    # negation, and saves a numpy call per solve.
    def correction(self, errors: list) -> np.ndarray:
        """``-W Jᵀ λ`` for ``A λ = -C``: minus the motion (6 per island body) that closes ``errors``."""
        return self.wjt.dot(self.solve(np.array(errors)))

    def velocity(self, u: list):
        """``(-λ, -W Jᵀ λ)`` for ``A λ = -J u`` (``jac`` holds this step's rows only until the
        island is factorised again: the next step's correction needs ``W Jᵀ`` and ``A`` only)."""
        lam = self.solve(self.jac.dot(np.array(u)))
        return lam, self.wjt.dot(lam).tolist()


class _Island:
    """One island's rows as a dense ``(m, 6 nb)`` matrix whose variable entries are scattered in
    from the joints' ``entries`` each step (the ``±E`` of gap rows are set once)."""

    def __init__(self, island, joints, offsets, inv_mass) -> None:
        self.bodies = list(island.bodies)
        self.joints = [joints[k] for k in island.constraints]
        self.evaluators = [joint.evaluate for joint in self.joints]     # bound once
        self.rows = np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in island.constraints])
        m, width = len(self.rows), 6 * len(self.bodies)
        self.m = m
        column = {b: 6 * c for c, b in enumerate(self.bodies)}
        self.jac = np.zeros((m, width))
        index, first = [], 0
        for joint in self.joints:
            for body, free, sign in ((joint.a, joint.free_a, -1.0), (joint.b, joint.free_b, 1.0)):
                if not free:
                    continue
                c0 = column[body]
                index += [(first + r) * width + c0 + c for r, c in joint.columns()]
                if joint.kind != "bar":
                    for i in range(3):
                        self.jac[first + i, c0 + i] = sign
            first += joint.rows
        self.index = np.array(index, dtype=np.intp)
        self.weights = np.zeros((width, width))
        for c, body in enumerate(self.bodies):
            for i in range(3):
                self.weights[6 * c + i, 6 * c + i] = inv_mass[body]
        self.weight_index = np.array([(6 * c + 3 + i) * width + 6 * c + 3 + j for c in range(len(self.bodies))
                                      for i in range(3) for j in range(3)], dtype=np.intp)
        self.redundant = False
        self.flat_jac, self.flat_weights = self.jac.reshape(-1), self.weights.reshape(-1)   # views

    def errors(self, com, rot) -> list[float]:
        out: list[float] = []
        extend = out.extend
        for evaluate in self.evaluators:
            extend(evaluate(com, rot))
        return out

    def factorise(self, inv_inertia) -> _Factor:
        """``J W Jᵀ`` at the configuration of the joints' last ``evaluate``, and its inverse or
        pseudo-inverse (``_pseudo_inverse``)."""
        values: list[float] = []
        for joint in self.joints:
            values += joint.entries()
        self.flat_jac[self.index] = values
        weights: list[float] = []
        for body in self.bodies:
            weights += inv_inertia[body]
        self.flat_weights[self.weight_index] = weights
        wjt = self.weights.dot(self.jac.T)
        # J (W Jᵀ) is symmetric but for rounding, which the refinement step absorbs (the
        # eigendecomposition reads one triangle).
        system = self.jac.dot(wjt)
        pinv, rank = self._pseudo_inverse(system)
        return _Factor(self.jac, wjt, system, pinv, rank)

    def _pseudo_inverse(self, system):
        """``(A⁺, rank)`` with the rank rule of ``solver._DenseStack``: eigenvalues below
        ``RANK_RTOL ×`` the largest diagonal entry count as zero.

        The eigendecomposition costs 2-3 times an inverse, so an island is first inverted:
        ``‖A⁻¹‖_F >= ‖A⁻¹‖₂ = 1/λ_min``, so ``‖A⁻¹‖_F RANK_RTOL d < 1/2`` proves every
        eigenvalue is above twice the threshold (its rounding is far smaller), and the inverse
        is the pseudo-inverse. Otherwise (a redundant island, which stays so: it is not tried
        again), the eigendecomposition decides.
        """
        threshold = RANK_RTOL * max(float(system.diagonal().max()), 0.0)
        if not self.redundant:
            try:
                inverse = _inverse(system)
            except np.linalg.LinAlgError:
                inverse = None
            if inverse is not None and threshold > 0 and math.sqrt(float(np.vdot(inverse, inverse))) * threshold < 0.5:
                return inverse, self.m
            self.redundant = True
        eig, vectors = _eigh(system)
        keep = eig > threshold
        inv = np.divide(1.0, eig, out=np.zeros_like(eig), where=keep)
        return (vectors * inv).dot(vectors.T), int(keep.sum())


class _Single:
    """An island of one row (a bar) in floats: its system is the number ``a = J W Jᵀ``.

    Same rules as ``_Island``: rank 1 when ``a > RANK_RTOL a``, one refinement step.
    """

    def __init__(self, island, joints, offsets, inv_mass) -> None:
        self.joint = joints[island.constraints[0]]
        self.bodies = list(island.bodies)
        self.rows = np.array([offsets[island.constraints[0]]])
        self.m = 1
        self.inv_mass = [inv_mass[b] for b in self.bodies]

    def errors(self, com, rot) -> list[float]:
        return self.joint.evaluate(com, rot)

    def factorise(self, inv_inertia) -> "_SingleFactor":
        row = self.joint.entries()          # 6 per free side, the free sides in body order
        if self.joint.free_a and self.joint.free_b and self.joint.a > self.joint.b:
            row = row[6:] + row[:6]
        wjt: list[float] = []
        for c, body in enumerate(self.bodies):
            j0, j1, j2, j3, j4, j5 = row[6 * c:6 * c + 6]
            im, w = self.inv_mass[c], inv_inertia[body]
            wjt += [im * j0, im * j1, im * j2, w[0] * j3 + w[1] * j4 + w[2] * j5,
                    w[3] * j3 + w[4] * j4 + w[5] * j5, w[6] * j3 + w[7] * j4 + w[8] * j5]
        # Plain sums, not math.fsum, which raises on an overflow that must reach the checks as inf.
        a = sum([j * w for j, w in zip(row, wjt)])
        keep = a > RANK_RTOL * max(a, 0.0)
        if not math.isfinite(a):
            raise np.linalg.LinAlgError("the constraint system is not finite")
        return _SingleFactor(row, wjt, a, 1.0 / a if keep else 0.0, int(keep))


class _SingleFactor:
    __slots__ = ("row", "wjt", "system", "pinv", "rank")

    def __init__(self, row, wjt, system, pinv, rank) -> None:
        self.row, self.wjt, self.system, self.pinv, self.rank = row, wjt, system, pinv, rank

    def _solve(self, b: float) -> float:
        lam = self.pinv * b
        return lam + self.pinv * (b - self.system * lam)

    def correction(self, errors: list) -> tuple:
        lam = self._solve(errors[0])
        return tuple([w * lam for w in self.wjt])

    def velocity(self, u: list):
        lam = self._solve(sum([j * v for j, v in zip(self.row, u)]))
        return np.array([lam]), [w * lam for w in self.wjt]


class SmallStep:
    """The state of a small ``World`` as floats, and its steps (``simulation`` drives them)."""

    def __init__(self, world) -> None:
        rs = world.rowset
        self.n, self.m, self.offsets = len(world.mass), rs.m, rs.offsets
        self.moving = world.moving.tolist()
        self.inv_mass = world.inv_mass.tolist()
        self.inertia = world.inertia_body.reshape(-1, 9).tolist()
        self.inv_inertia_body = world.inv_inertia_body.reshape(-1, 9).tolist()
        # Principal-axis bodies (most: shapes, diagonal inertias) take the diagonal forms.
        self.diagonal: list = [None] * self.n
        for i, (m, e) in enumerate(zip(self.inertia, self.inv_inertia_body)):
            if not any(m[j] or e[j] for j in (1, 2, 3, 5, 6, 7)):
                self.diagonal[i] = ((m[0], m[4], m[8]), (e[0], e[4], e[8]))
        self.com, self.vel = world.com.ravel().tolist(), world.vel.ravel().tolist()
        self.omega = world.omega.ravel().tolist()
        self.quat = [tuple(q) for q in world.quat.tolist()]
        self.rot = world.rot.reshape(-1, 9).tolist()
        active = world.active.tolist()
        hinge = {k: h for h, k in enumerate(rs.hinges.tolist())}
        joints = []
        for k, spec in enumerate(world.scene.constraints):
            a, b = int(rs.a[k]), int(rs.b[k])
            h = hinge.get(k)
            axes = None if h is None else (rs.axis_a[h].tolist(), rs.axis_b[h].tolist())
            joint = make_joint(spec.type, a, b, rs.off_a[k].tolist(), rs.off_b[k].tolist(), active[a], active[b],
                               self.com, self.rot, spec.where, axes, float(spec.length or 0.0))
            joints.append(joint)
        self.islands = [(_Single if len(isl.constraints) == 1 and joints[isl.constraints[0]].rows == 1 else _Island)
                        (isl, joints, rs.offsets, self.inv_mass) for isl in world.islands]
        self.lam: list = [np.zeros(island.m) for island in self.islands]   # minus the last multipliers
        for island in self.islands:
            island.errors(self.com, self.rot)
        inv_inertia = self._inv_inertia()
        self.factors = [island.factorise(inv_inertia) for island in self.islands]

    def _inv_inertia(self) -> list:
        """World inverse inertia ``R I⁻¹ Rᵀ`` of every body (9 floats; None for bodies not moving)."""
        out: list = [None] * self.n
        for i in self.moving:
            diagonal = self.diagonal[i]
            out[i] = (conjugate(self.rot[i], self.inv_inertia_body[i]) if diagonal is None
                      else conjugate_diagonal(self.rot[i], diagonal[1]))
        return out

    # -- one step ---------------------------------------------------------------------------------
    def kick(self, half_kick) -> None:
        vel = self.vel
        g0, g1, g2 = half_kick
        for i in self.moving:
            vel[3 * i] += g0
            vel[3 * i + 1] += g1
            vel[3 * i + 2] += g2

    def drift(self, dt: float) -> None:
        """``World.drift``: centres by ``v dt``, orientations by ``exp(ω dt)``, keeping ``I_world ω``."""
        com, vel, omega, rot, quat, diagonal = self.com, self.vel, self.omega, self.rot, self.quat, self.diagonal
        for i in self.moving:
            r, k = rot[i], 3 * i
            w = (omega[k], omega[k + 1], omega[k + 2])
            com[k] += vel[k] * dt
            com[k + 1] += vel[k + 1] * dt
            com[k + 2] += vel[k + 2] * dt
            quat[i], turned = turn(quat[i], w[0] * dt, w[1] * dt, w[2] * dt)
            rot[i] = turned
            d = diagonal[i]
            if d is None:
                spin = carry_spin(r, turned, self.inertia[i], self.inv_inertia_body[i], w)
            else:
                spin = carry_spin_diagonal(r, turned, d[0], d[1], w)
            omega[k], omega[k + 1], omega[k + 2] = spin

    def correct(self, tolerance: float, dt: float, iterations: int = 8) -> float:
        """``World.correct_positions`` along the frozen system of the step's start, crediting
        the displacement to the velocities (``/ dt``); returns the largest remaining error."""
        com, rot, quat, islands, factors = self.com, self.rot, self.quat, self.islands, self.factors
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
                        quat[i], rot[i] = turn(quat[i], -d3, -d4, -d5)
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

    def solve_velocities(self) -> None:
        """``World.solve_velocities`` at the configuration of the last ``correct``; its
        factorisation is kept as the next step's frozen system."""
        inv_inertia = self._inv_inertia()
        vel, omega = self.vel, self.omega
        self.factors = []
        for n, island in enumerate(self.islands):
            factor = island.factorise(inv_inertia)
            self.factors.append(factor)
            u: list[float] = []
            for i in island.bodies:
                u += vel[3 * i:3 * i + 3]
                u += omega[3 * i:3 * i + 3]
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
