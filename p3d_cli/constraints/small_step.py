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

from p3d_cli.constraints.scalar import Joint, apply, apply_t, conjugate, matrix, rotate
from p3d_cli.constraints.solver import RANK_RTOL, ImpulseSolution

#: Scenes with at most this many rows, and this many free bodies, take this path.
SMALL_ROWS = 60
SMALL_BODIES = 12


def fits(world) -> bool:
    """Whether ``world``'s scene is small and all its islands are solved densely."""
    return (world.plan.m <= SMALL_ROWS and len(world.moving) <= SMALL_BODIES
            and all(path == "dense" for path, _, _ in world.plan.order))


class _Factor:
    """One island's factorised system: ``K`` the pseudo-inverse of ``A = J W Jᵀ`` and ``W Jᵀ``."""

    __slots__ = ("wjt", "system", "pinv", "rank")

    def __init__(self, wjt, system, pinv, rank) -> None:
        self.wjt, self.system, self.pinv, self.rank = wjt, system, pinv, rank

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Minimum-norm ``λ`` of ``A λ = b`` with one step of iterative refinement, which recovers
        the digits the eigendecomposition's rounding loses on an ill-conditioned island (so an
        explicit pseudo-inverse is as accurate here as applying the eigenvectors)."""
        pinv = self.pinv
        lam = pinv @ b
        return lam + pinv @ (b - self.system @ lam)


class _Island:
    """One island's rows as a dense ``(m, 6 nb)`` matrix whose variable entries are scattered in
    from the joints' ``entries`` each step (the ``±E`` of gap rows are set once)."""

    def __init__(self, island, joints, offsets, active, inv_mass) -> None:
        self.bodies = list(island.bodies)
        self.joints = [joints[k] for k in island.constraints]
        self.sides = [(j, bool(active[j.a]), bool(active[j.b])) for j in self.joints]
        self.rows = np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in island.constraints])
        m, width = len(self.rows), 6 * len(self.bodies)
        self.m = m
        column = {b: 6 * c for c, b in enumerate(self.bodies)}
        self.jac = np.zeros((m, width))
        index, first = [], 0
        for joint, free_a, free_b in self.sides:
            for body, free, sign in ((joint.a, free_a, -1.0), (joint.b, free_b, 1.0)):
                if not free:
                    continue
                c0 = column[body]
                index += [(first + r) * width + c0 + c for r, c in joint.columns()]
                if joint.kind != "bar":
                    for i in range(3):
                        self.jac[first + i, c0 + i] = sign
            first += {"ball": 3, "hinge": 5, "bar": 1}[joint.kind]
        self.index = np.array(index, dtype=np.intp)
        self.weights = np.zeros((width, width))
        for c, body in enumerate(self.bodies):
            for i in range(3):
                self.weights[6 * c + i, 6 * c + i] = inv_mass[body]
        self.weight_index = np.array([(6 * c + 3 + i) * width + 6 * c + 3 + j for c in range(len(self.bodies))
                                      for i in range(3) for j in range(3)], dtype=np.intp)

    def errors(self, com, rot) -> list[float]:
        out: list[float] = []
        for joint in self.joints:
            out += joint.evaluate(com, rot)
        return out

    def factorise(self, inv_inertia) -> _Factor:
        """``J W Jᵀ`` at the configuration of the joints' last ``evaluate``, factorised as
        ``solver._DenseStack`` does (eigendecomposition, relative rank tolerance)."""
        values: list[float] = []
        for joint, free_a, free_b in self.sides:
            values += joint.entries(free_a, free_b)
        self.jac.flat[self.index] = values
        weights: list[float] = []
        for body in self.bodies:
            weights += inv_inertia[body]
        self.weights.flat[self.weight_index] = weights
        wjt = self.weights @ self.jac.T
        system = self.jac @ wjt
        system = 0.5 * (system + system.T)
        eig, vectors = np.linalg.eigh(system)
        keep = eig > RANK_RTOL * max(float(system.diagonal().max()), 0.0)
        inv = np.divide(1.0, eig, out=np.zeros_like(eig), where=keep)
        return _Factor(wjt, system, (vectors * inv) @ vectors.T, int(keep.sum()))


class SmallStep:
    """The state of a small ``World`` as floats, and its steps (``simulation`` drives them)."""

    def __init__(self, world) -> None:
        rs = world.rowset
        self.n, self.m, self.offsets = len(world.mass), rs.m, rs.offsets
        self.moving = world.moving.tolist()
        self.inv_mass = world.inv_mass.tolist()
        self.inertia = world.inertia_body.reshape(-1, 9).tolist()
        self.inv_inertia_body = world.inv_inertia_body.reshape(-1, 9).tolist()
        hinge = {k: h for h, k in enumerate(rs.hinges.tolist())}
        joints = []
        for k, spec in enumerate(world.scene.constraints):
            h = hinge.get(k)
            axes = (rs.axis_a[h].tolist(), rs.axis_b[h].tolist()) if h is not None else (None, None)
            joints.append(Joint(spec.type, int(rs.a[k]), int(rs.b[k]), rs.off_a[k].tolist(), rs.off_b[k].tolist(),
                                *axes, spec.length, spec.where))
        self.islands = [_Island(isl, joints, rs.offsets, world.active, self.inv_mass) for isl in world.islands]
        self.com, self.vel = world.com.ravel().tolist(), world.vel.ravel().tolist()
        self.omega = world.omega.ravel().tolist()
        self.quat = [tuple(q) for q in world.quat.tolist()]
        self.rot = world.rot.reshape(-1, 9).tolist()
        self.lam = np.zeros(self.m)
        for island in self.islands:
            island.errors(self.com, self.rot)
        self.factors = [island.factorise(self._inv_inertia()) for island in self.islands]

    def _inv_inertia(self) -> list:
        """World inverse inertia ``R I⁻¹ Rᵀ`` of every body (9 floats; None for bodies not moving)."""
        out: list = [None] * self.n
        for i in self.moving:
            out[i] = conjugate(self.rot[i], self.inv_inertia_body[i])
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
        com, vel, omega = self.com, self.vel, self.omega
        for i in self.moving:
            r, k = self.rot[i], 3 * i
            w = (omega[k], omega[k + 1], omega[k + 2])
            spin = apply(r, apply(self.inertia[i], apply_t(r, w)))
            com[k] += vel[k] * dt
            com[k + 1] += vel[k + 1] * dt
            com[k + 2] += vel[k + 2] * dt
            q = self.quat[i] = rotate(self.quat[i], w[0] * dt, w[1] * dt, w[2] * dt)
            r = self.rot[i] = matrix(q)
            omega[k], omega[k + 1], omega[k + 2] = apply(r, apply(self.inv_inertia_body[i], apply_t(r, spin)))

    def correct(self, tolerance: float, dt: float, iterations: int = 8) -> float:
        """``World.correct_positions`` along the frozen system of the step's start, crediting
        the displacement to the velocities (``/ dt``); returns the largest remaining error."""
        com, rot, quat = self.com, self.rot, self.quat
        total = [0.0] * (6 * self.n)
        for _ in range(iterations + 1):
            errors = [island.errors(com, rot) for island in self.islands]
            worst = max((abs(e) for part in errors for e in part), default=0.0)
            if worst <= tolerance or _ == iterations:
                break
            for island, factor, part in zip(self.islands, self.factors, errors):
                change = (factor.wjt @ factor.solve(-np.array(part))).tolist()
                for c, i in enumerate(island.bodies):
                    d = change[6 * c:6 * c + 6]
                    k = 3 * i
                    com[k] += d[0]
                    com[k + 1] += d[1]
                    com[k + 2] += d[2]
                    if d[3] or d[4] or d[5]:
                        quat[i] = rotate(quat[i], d[3], d[4], d[5])
                        rot[i] = matrix(quat[i])
                    for j in range(6):
                        total[6 * i + j] += d[j]
        vel, omega = self.vel, self.omega
        for i in self.moving:
            for j in range(3):
                vel[3 * i + j] += total[6 * i + j] / dt
                omega[3 * i + j] += total[6 * i + 3 + j] / dt
        return worst

    def solve_velocities(self) -> None:
        """``World.solve_velocities`` at the configuration of the last ``correct``; its
        factorisation is kept as the next step's frozen system."""
        inv_inertia = self._inv_inertia()
        vel, omega = self.vel, self.omega
        self.factors = []
        for island in self.islands:
            factor = island.factorise(inv_inertia)
            self.factors.append(factor)
            u = []
            for i in island.bodies:
                u += vel[3 * i:3 * i + 3]
                u += omega[3 * i:3 * i + 3]
            lam = factor.solve(-(island.jac @ np.array(u)))
            self.lam[island.rows] = lam
            change = (factor.wjt @ lam).tolist()
            for c, i in enumerate(island.bodies):
                for j in range(3):
                    vel[3 * i + j] += change[6 * c + j]
                    omega[3 * i + j] += change[6 * c + 3 + j]

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
        return ImpulseSolution(self.lam.copy(), self.offsets, sum(r for r, _ in ranks), sum(e for _, e in ranks),
                               ranks)
