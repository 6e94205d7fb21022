"""A stepped scene's motion as arrays: states, energy and joint errors over time (for plots).

``record_motion`` runs ``solve_scene`` once, keeping the bodies' states at up to ``samples``
evenly spaced steps (and the start), then evaluates at each kept state, on a world built from
the same scene and mass properties: the kinetic energy, the potential energy of the scene's
gravity (``-Σ m g·x``, zero at the world origin), and every constraint's position error (the
``position_error`` of ``p3d solve``'s report, as each constraint module defines it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Most states kept for a plot (every k-th step beyond that).
SAMPLES = 2000


@dataclass(frozen=True)
class Motion:
    """Sampled states of a stepped scene.

    Attributes
    ----------
    time : (k,) float64
    bodies : tuple of str
        Scene order.
    fixed : (n,) bool
    position : (k, n, 3) float64
        Centres of mass (body origins for bodies whose mass properties are unknown), world frame.
    origin : (k, n, 3) float64
        Body frames' origins, world frame.
    rotation : (k, n, 4) float64
        Unit quaternions ``[w, x, y, z]``, body to world.
    velocity, angular_velocity : (k, n, 3) float64
    kinetic, potential : (k,) float64
        Energies of the free bodies.
    joints : tuple of str
        ``type a-b`` of each constraint.
    joint_errors : (k, m) float64
        Each constraint's position error.
    every : int
        Steps between kept states.
    """

    time: np.ndarray
    bodies: tuple[str, ...]
    fixed: np.ndarray
    position: np.ndarray
    origin: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray
    joints: tuple[str, ...]
    joint_errors: np.ndarray
    every: int

    @property
    def energy(self) -> np.ndarray:
        """(k,) total mechanical energy."""
        return self.kinetic + self.potential

    def turn_angles(self) -> np.ndarray:
        """(k, n, 3) rotation vector (radians) of each body from its first orientation, world
        frame: a hinge's swing is the component along its axis."""
        q0 = self.rotation[0]
        w0, v0 = q0[..., :1], -q0[..., 1:]                       # the inverse of the first
        w, v = self.rotation[..., :1], self.rotation[..., 1:]
        # q * q0⁻¹ (Hamilton product), as (w, xyz)
        rw = w * w0 - np.sum(v * v0, axis=-1, keepdims=True)
        rv = w * v0 + w0 * v + np.cross(v, v0)
        rv = np.where(rw < 0, -rv, rv)
        rw = np.abs(rw)
        norm = np.linalg.norm(rv, axis=-1, keepdims=True)
        angle = 2 * np.arctan2(norm, rw)
        with np.errstate(invalid="ignore", divide="ignore"):
            axis = np.where(norm > 0, rv / np.where(norm > 0, norm, 1.0), 0.0)
        return axis * angle


def record_motion(scene, *, steps: int, dt: float, samples: int = SAMPLES, on_step=None):
    """Step ``scene`` as ``solve_scene`` does and keep its motion.

    Parameters
    ----------
    scene : Scene
    steps, dt
        As for ``solve_scene`` (``steps`` at least 1).
    samples : int
        Most states kept besides the start.
    on_step : callable, optional
        Also called after every step, as for ``solve_scene`` (a trajectory writer).

    Returns
    -------
    (SolveResult, Motion)

    Raises
    ------
    UsageError, SceneError, RangeError
        As ``solve_scene``.
    """
    from p3d_cli.constraints.bodies import resolve_inertials
    from p3d_cli.constraints.simulation import needed_bodies, solve_scene
    from p3d_cli.constraints.world import World
    from p3d_cli.errors import UsageError

    if steps < 1:
        raise UsageError("steps", "a motion needs at least one step", "give steps= of 1 or more")
    every = max(1, -(-steps // max(int(samples), 1)))
    states: list[tuple[float, tuple]] = []

    def keep(t, bodies) -> None:
        if on_step is not None:
            on_step(t, bodies)
        if round(t / dt) % every == 0 or round(t / dt) == steps:
            states.append((t, bodies))

    result = solve_scene(scene, steps=steps, dt=dt, on_step=keep)
    inertials = resolve_inertials(needed_bodies(scene, True, True))
    world = World(scene, inertials)
    start = (0.0, tuple(_initial(world)))
    return result, _motion(world, [start] + states, every)


def _initial(world):
    from p3d_cli.constraints.simulation import _bodies

    return _bodies(world)


def _motion(world, states, every: int) -> Motion:
    n = len(world.scene.bodies)
    k = len(states)
    position, origin, rotation = np.zeros((k, n, 3)), np.zeros((k, n, 3)), np.zeros((k, n, 4))
    velocity, omega = np.zeros((k, n, 3)), np.zeros((k, n, 3))
    for i, (_, bodies) in enumerate(states):
        for j, body in enumerate(bodies):
            position[i, j] = body.center_of_mass if body.center_of_mass is not None else body.position
            origin[i, j] = body.position
            rotation[i, j], velocity[i, j], omega[i, j] = body.rotation, body.velocity, body.angular_velocity
    kinetic, potential = np.zeros(k), np.zeros(k)
    errors = np.zeros((k, len(world.scene.constraints)))
    gravity = np.asarray(world.scene.gravity, dtype=np.float64)
    for i in range(k):
        # The world's arrays take each kept state; what depends on the pose is then recomputed.
        world.com[:] = position[i]
        world.quat[:] = rotation[i]
        world.vel[:] = velocity[i] * world.active[:, None]
        world.omega[:] = omega[i] * world.active[:, None]
        world._moved()
        kinetic[i] = world.kinetic_energy()
        potential[i] = -float(np.sum(world.mass * (world.com @ gravity)))
        errors[i] = [float(np.linalg.norm(e)) for e in world.position_residuals(world.geometries())]
    joints = tuple(f"{c.type} {c.a}-{c.b}" for c in world.scene.constraints)
    return Motion(np.array([t for t, _ in states]), tuple(b.name for b in world.scene.bodies),
                  np.array([b.fixed for b in world.scene.bodies], dtype=bool), position, origin, rotation,
                  velocity, omega, kinetic, potential, joints, errors, every)
