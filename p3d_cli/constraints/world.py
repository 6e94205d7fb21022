"""The mutable world state of one solve: arrays over all bodies, and the operations on them.

Only this module and ``simulation`` mutate arrays; everything they return is frozen.
Conventions (docs/solve.md): world frame throughout; ``I⁻¹_world = R I⁻¹_body Rᵀ``;
``r = attachment - centre of mass``; velocities are those of the centres of mass; fixed bodies
(and bodies at rest that nothing links, whose mass properties are never computed) have zero
inverse mass and inverse inertia.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from p3d_cli.constraints.islands import find_islands
from p3d_cli.constraints.joint import joint_geometry
from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.constraints.rotation import quat_to_matrix, quat_to_matrix_many, rotate_by_many
from p3d_cli.constraints.rows import RowSet
from p3d_cli.constraints.solver import PendingSolution, SystemPlan


class World:
    """Arrays over the scene's bodies (scene order) and its constraints."""

    # What depends on the pose, built when first asked for and dropped when the bodies move.
    _geo: Any = None
    _rows_cache: Any = None
    _factor: Any = None

    def __init__(self, scene, inertials: dict) -> None:
        n = len(scene.bodies)
        self.scene = scene
        self.index = {b.name: i for i, b in enumerate(scene.bodies)}
        self.fixed = np.array([b.fixed for b in scene.bodies], dtype=bool)
        self.active = np.array([(not b.fixed) and b.name in inertials for b in scene.bodies], dtype=bool)
        self.known = np.array([b.name in inertials for b in scene.bodies], dtype=bool)
        self.mass = np.zeros(n)
        self.inertia_body = np.zeros((n, 3, 3))
        self.inv_inertia_body = np.zeros((n, 3, 3))
        self.com_body = np.zeros((n, 3))
        for i, body in enumerate(scene.bodies):
            inertial = inertials.get(body.name)
            if inertial is None:
                continue
            self.com_body[i] = inertial.center_of_mass
            if self.active[i]:
                self.mass[i] = inertial.mass
                self.inertia_body[i] = inertial.inertia
                self.inv_inertia_body[i] = np.linalg.inv(inertial.inertia)
        self.inv_mass = np.where(self.active, 1.0 / np.where(self.active, self.mass, 1.0), 0.0)
        self.quat = np.array([b.rotation for b in scene.bodies]).reshape(n, 4)
        self.rot = quat_to_matrix(self.quat)
        origins = np.array([b.position for b in scene.bodies]).reshape(n, 3)
        self.com = origins + np.einsum("nij,nj->ni", self.rot, self.com_body)
        self.vel = np.array([b.velocity for b in scene.bodies]).reshape(n, 3) * self.active[:, None]
        self.omega = np.array([b.angular_velocity for b in scene.bodies]).reshape(n, 3) * self.active[:, None]
        self.pairs = [(self.index[c.a], self.index[c.b]) for c in scene.constraints]
        self.modules = [CONSTRAINT_TYPES[c.type] for c in scene.constraints]
        self.islands = find_islands(self.pairs, ~self.active)
        self.island_of = {}
        for number, island in enumerate(self.islands):
            for k in island.constraints:
                self.island_of[k] = number
        self.constrained = np.zeros(n, dtype=bool)
        for a, b in self.pairs:
            self.constrained[a] = self.constrained[b] = True
        self.rowset = RowSet(scene, self.index, self.com_body)
        self.plan = SystemPlan(self.islands, self.rowset, self.active)
        self.moving = np.flatnonzero(self.active)
        self._update_inverse_inertia()

    # -- derived quantities -------------------------------------------------------------
    def _update_inverse_inertia(self) -> None:
        self._moved()

    def inertia_world(self) -> np.ndarray:
        return self.rot @ self.inertia_body @ np.transpose(self.rot, (0, 2, 1))

    def origins(self) -> np.ndarray:
        """World positions of the body frames' origins, (n, 3)."""
        return self.com - np.einsum("nij,nj->ni", self.rot, self.com_body)

    def geometries(self) -> list:
        out = []
        for spec, (a, b) in zip(self.scene.constraints, self.pairs):
            out.append(joint_geometry(spec, self.com[a], self.rot[a], self.com_body[a],
                                      self.com[b], self.rot[b], self.com_body[b]))
        return out

    def kinetic_energy(self) -> float:
        linear = 0.5 * np.sum(self.mass * np.sum(self.vel ** 2, axis=1))
        angular = 0.5 * np.einsum("ni,nij,nj->", self.omega, self.inertia_world(), self.omega)
        return float(linear + angular)

    def momentum(self) -> np.ndarray:
        return np.sum(self.mass[:, None] * self.vel, axis=0)

    def angular_momentum(self) -> np.ndarray:
        """About the world origin: ``Σ m x × v + I_world ω``."""
        orbital = np.cross(self.com, self.mass[:, None] * self.vel)
        spin = np.einsum("nij,nj->ni", self.inertia_world(), self.omega)
        return np.sum(orbital + spin, axis=0)

    # -- the two projections ------------------------------------------------------------
    def _blocks(self, geos) -> list:
        return [module.jacobian(geo) for module, geo in zip(self.modules, geos)]

    def velocity_residuals(self, geos, blocks) -> list:
        u = np.hstack([self.vel, self.omega])
        return [ja @ u[a] + jb @ u[b] for (a, b), (ja, jb) in zip(self.pairs, blocks)]

    def position_residuals(self, geos) -> list:
        return [module.position_error(spec, geo)
                for module, spec, geo in zip(self.modules, self.scene.constraints, geos)]

    def _geometry_now(self):
        """The rows' geometry at the current positions, computed once per configuration."""
        if self._geo is None:
            self._geo = self.rowset.geometry(self.com, self.rot)
        return self._geo

    def _rows_now(self):
        """``(JA, JB)`` at the current positions, computed once per configuration (a step
        needs them once, for its closing velocity solve; correction iterations do not)."""
        if self._rows_cache is None:
            self._rows_cache = self.rowset.jacobian(self._geometry_now())
        return self._rows_cache

    def _moved(self) -> None:
        self.rot = quat_to_matrix_many(self.quat)
        self._inv_inertia = None
        self._geo = self._rows_cache = self._factor = None

    @property
    def inv_inertia(self) -> np.ndarray:
        """World inverse inertia ``R I⁻¹ Rᵀ``, (n, 3, 3); computed when first needed after a move."""
        if self._inv_inertia is None:
            self._inv_inertia = self.rot @ self.inv_inertia_body @ np.transpose(self.rot, (0, 2, 1))
        return self._inv_inertia


    def solve_velocities(self):
        """One velocity solve: apply the impulses that make every constraint's velocity
        equations hold. Returns a ``PendingSolution``
        (its multipliers are solved for when asked).

        The factorised system is kept: it is the frozen system of the next step's position
        correction (``frozen_rows``), whose rows are these.
        """
        ja, jb = self._rows_now()
        if self._factor is None:
            self._factor = self.plan.factorise(ja, jb, self.inv_mass, self.inv_inertia)
        b = -self.rowset.apply(ja, jb, np.hstack([self.vel, self.omega]))
        change = self._factor.motion(b)
        self.vel += change[:, :3]
        self.omega += change[:, 3:]
        return PendingSolution(self._factor, b)

    def correct_positions(self, tolerance: float, frozen=None, iterations: int = 8):
        """Position projection onto ``C(x) = 0`` along mass-weighted constraint directions.

        Parameters
        ----------
        tolerance : float
            Stop once every position error is at most this.
        frozen : Factorisation, optional
            The factorised system of the constraint rows and world inverse inertia taken at
            the start of a time step (``frozen_rows``; it keeps those rows). The displacement is then ``W₀ J₀ᵀ λ`` with
            ``λ`` found by iterating ``(J₀ W₀ J₀ᵀ) Δλ = -C(x)`` (SHAKE's frozen-gradient
            projection, which RATTLE needs to be symplectic; it converges at a rate of order
            ``ω dt`` per iteration), so one factorisation serves every iteration. Without it,
            each iteration re-linearises at the current positions (Newton), which is what
            assembling a scene needs.
        iterations : int

        Returns
        -------
        worst : float
            The largest remaining position error.
        dx, dtheta : (n, 3) float64
            Total displacement of each centre of mass and rotation vector applied.
        """
        n = len(self.mass)
        total_dx, total_dtheta = np.zeros((n, 3)), np.zeros((n, 3))
        for _ in range(iterations):
            geo = self._geometry_now()
            errors = self.rowset.errors(geo)
            worst = float(np.abs(errors).max()) if errors.size else 0.0
            if worst <= tolerance:
                return worst, total_dx, total_dtheta
            if frozen is not None:
                factor = frozen
            else:
                ja, jb = self._rows_now()
                factor = self.plan.factorise(ja, jb, self.inv_mass, self.inv_inertia)
            change = factor.motion(-errors)
            dx, dtheta = change[:, :3], change[:, 3:]
            self.com += dx
            if dtheta.any():
                self.quat = rotate_by_many(self.quat, dtheta)
                self._moved()
            else:
                # Rows acting through the centres of mass only (a bob on a bar) turn nothing:
                # the orientations, and what depends on them, stay as they are.
                self._geo = self._rows_cache = self._factor = None
            total_dx += dx
            total_dtheta += dtheta
        errors = self.rowset.errors(self._geometry_now())
        return (float(np.abs(errors).max()) if errors.size else 0.0), total_dx, total_dtheta

    def frozen_rows(self):
        """The factorised system of the rows and world inverse inertia now, for
        ``correct_positions(frozen=...)`` (the last velocity solve's, when nothing moved since)."""
        if self._factor is None:
            ja, jb = self._rows_now()
            self._factor = self.plan.factorise(ja, jb, self.inv_mass, self.inv_inertia)
        return self._factor

    def drift(self, dt: float) -> None:
        """Advance positions and orientations by ``dt`` at the current velocities.

        The orientation turns by ``exp(ω dt)`` (unit quaternions, renormalised). Each free
        body's angular momentum ``I_world ω`` is kept through the turn, so ``ω`` follows the
        rotated inertia (torque-free motion of an asymmetric body is not lost).
        """
        moving = self.moving
        spin = (self.inertia_world()[moving] @ self.omega[moving, :, None])
        self.com[moving] += self.vel[moving] * dt
        self.quat[moving] = rotate_by_many(self.quat[moving], self.omega[moving] * dt)
        self._moved()
        self.omega[moving] = (self.inv_inertia[moving] @ spin)[:, :, 0]

