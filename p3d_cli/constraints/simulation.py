"""``solve_scene``: one velocity solve, or stepping in time, of a validated scene.

This is the function behind ``p3d solve``; the CLI only parses options and formats the
``SolveResult`` it returns.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints import small_step
from p3d_cli.constraints.bodies import resolve_inertials
from p3d_cli.constraints.outcome import BodyState, ConstraintOutcome, SolveResult
from p3d_cli.constraints.world import World
from p3d_cli.errors import RangeError, UsageError

#: Position correction stops once every position error is below this fraction of the
#: scene's length scale (the largest attachment offset).
POSITION_RTOL = 1e-12

#: Limits on stepping, checked before any work (docs/solve.md, "Limits"): a step of a small
#: scene takes about 0.2 ms, so these bound a run to hours, not the ages ``--steps 1e20`` asks.
MAX_STEPS = 10_000_000
#: ... and on steps × (bodies + constraints), which a step's cost (and a trajectory's rows) grow with.
MAX_STEP_WORK = 100_000_000

#: Header of the trajectory rows ``trajectory_rows`` produces.
TRAJECTORY_HEADER = ("t", "body", "x", "y", "z", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")


def needed_bodies(scene, stepping: bool, centers: bool) -> list:
    """The bodies whose mass properties the solve needs (see ``docs/solve.md``).

    A free body needs them when a constraint links it, when it moves, or when it will fall
    under gravity; a fixed body only when its centre of mass is reported (``centers``).
    """
    linked = {c.a for c in scene.constraints} | {c.b for c in scene.constraints}
    falling = stepping and bool(np.any(scene.gravity))
    out = []
    for body in scene.bodies:
        free_needed = not body.fixed and (body.name in linked or body.moving or falling)
        if centers or free_needed or _known_without_integration(body):
            out.append(body)
    return out


def _known_without_integration(body) -> bool:
    # Reporting these costs nothing, so their centre of mass is reported too.
    if body.shape is None and body.parts is None:
        return True
    if body.center_of_mass is None:
        return False
    return body.fixed or (body.mass is not None and body.inertia is not None)


def solve_scene(scene, *, steps: int = 0, dt: float | None = None, on_step=None) -> SolveResult:
    """Solve a scene's constraints once, or advance it ``steps`` steps of ``dt``.

    Parameters
    ----------
    scene : Scene
    steps : int
        0: one velocity solve (no motion). N > 0: N steps of velocity solve, integration of
        positions and orientations, and position correction, under the scene's gravity; at
        most ``MAX_STEPS``, and ``MAX_STEP_WORK`` / (bodies + constraints).
    dt : float, optional
        Time step; required when ``steps > 0``.
    on_step : callable, optional
        Called after every step as ``on_step(t, bodies)`` with the tuple of ``BodyState``;
        then every body's centre of mass is resolved (a trajectory reports them), fixed
        bodies' shapes integrated if need be.

    Raises
    ------
    SceneError, UsageError
        An invalid scene, or steps or dt out of their limits (before any work).
    RangeError
        A number the solve reaches (energy, momentum, a state, an impulse, the constraint
        system) overflows float64 or is not a number: never nan in a result.
    """
    check_steps(steps, dt, scene)
    inertials = resolve_inertials(needed_bodies(scene, steps > 0, on_step is not None))
    # Overflow is found by the explicit checks of ``_solve`` (``_check_inverses``, ``_check_totals``,
    # ``_check_state``, the impulses in ``_result``), which name what
    # overflowed: numpy's warnings would only repeat it, a dozen lines at a time.
    with np.errstate(all="ignore"):
        try:
            return _solve(scene, inertials, steps, dt, on_step)
        except np.linalg.LinAlgError:
            # The constraint system's entries grow as (attachment - centre of mass)² / inertia; an
            # eigen-decomposition fails only when they are no longer finite.
            raise _overflow(scene.where, "the constraint system (bodies far from their joints)",
                            "take a smaller dt, or give the scene in units that keep its numbers "
                            "nearer 1") from None


def check_steps(steps: int, dt: float | None = None, scene=None) -> None:
    """Refuse a step count or time step before any work: negative, over ``MAX_STEPS``, or (with
    ``scene``) over ``MAX_STEP_WORK`` steps × (bodies + constraints); a non-positive ``dt``.

    Raises
    ------
    UsageError
    """
    if steps < 0:
        raise UsageError("steps", f"must be 0 or more, got {steps}", "give a whole number of steps")
    if steps > MAX_STEPS:
        raise UsageError("steps", f"{steps} is over the limit of {MAX_STEPS:,} steps",
                         "take a larger dt, or run the scene in parts from its last state")
    if scene is not None:
        size = len(scene.bodies) + len(scene.constraints)
        if steps * size > MAX_STEP_WORK:
            raise UsageError("steps", f"{steps} steps of a scene of {len(scene.bodies)} bodies and "
                             f"{len(scene.constraints)} constraints is over the limit of {MAX_STEP_WORK:,} "
                             "steps × (bodies + constraints)",
                             f"give at most {MAX_STEP_WORK // size} steps, or a larger dt")
    if steps > 0 and (dt is None or not math.isfinite(dt) or dt <= 0):
        raise UsageError("dt", "stepping needs a positive, finite time step", "give dt=, e.g. dt=0.001")


def _solve(scene, inertials, steps, dt, on_step) -> SolveResult:
    world = World(scene, inertials)
    _check_inverses(world)
    before = (world.kinetic_energy(), world.momentum(), world.angular_momentum())
    _check_totals(scene, before, "before the solve")
    tolerance = POSITION_RTOL * _length_scale(scene)
    if steps == 0:
        solution = world.solve_velocities()
        _check_state(world, "after the velocity solve")
        worst = max((float(np.abs(e).max()) for e in world.position_residuals(world.geometries())), default=0.0)
        return _result(world, solution, before, 0, 0.0, worst)
    # RATTLE (Andersen 1983; Leimkuhler & Skeel 1994) with the velocity solve of eq. 20 as its
    # velocity projection: half kick; drift; project positions back onto the constraints along
    # the start-of-step constraint directions, crediting the correction to the velocities (so
    # the step is the constrained one, not a dissipative pull-back); half kick; velocity solve at
    # the new positions. Second order, and a pendulum's energy shows no drift, where projecting
    # velocities only (symplectic Euler + projection) loses amplitude at O(dt).
    # The scene is first assembled (joints brought together by a mass-weighted Newton
    # projection, velocities untouched): a gap credited to the velocity would become a kick.
    half_kick = 0.5 * dt * scene.gravity
    worst, _, _ = world.correct_positions(tolerance)
    solution = world.solve_velocities()
    _check_state(world, "after assembling the scene")
    if small_step.fits(world):
        return _step_small(world, before, steps, dt, half_kick, tolerance, worst, on_step)
    for step in range(1, steps + 1):
        frozen = world.frozen_rows()
        world.vel[world.active] += half_kick
        world.drift(dt)
        _check_state(world, step, dt)
        error, dx, dtheta = world.correct_positions(tolerance, frozen)
        world.vel += dx / dt
        world.omega += dtheta / dt
        worst = max(worst, error)
        world.vel[world.active] += half_kick
        solution = world.solve_velocities()
        _check_state(world, step, dt)   # the correction's kick
        if on_step is not None:
            on_step(step * dt, _bodies(world))
    return _result(world, solution, before, steps, steps * dt, worst)


def _step_small(world: World, before, steps: int, dt: float, half_kick, tolerance: float, worst: float,
                on_step) -> SolveResult:
    """The steps of ``_solve`` for a small scene, on ``small_step.SmallStep``'s float state."""
    state = small_step.SmallStep(world)
    kick = half_kick.tolist()
    for step in range(1, steps + 1):
        state.drift(dt, kick)                # the first half kick, then the drift
        if not state.finite():
            state.store(world)
            _check_state(world, step, dt)
        worst = max(worst, state.correct(tolerance, dt))
        state.solve_velocities(kick)         # the second half kick, then the velocity solve
        if not state.finite():
            state.store(world)
            _check_state(world, step, dt)   # the correction's kick
        if on_step is not None:
            state.store(world)
            on_step(step * dt, _bodies(world))
    state.store(world)
    return _result(world, state.solution(), before, steps, steps * dt, worst)


def _overflow(where: str, what: str, hint: str = "") -> RangeError:
    return RangeError(where, f"{what} overflows float64 (or is not a number)",
                      hint or "give the scene in units that keep its numbers nearer 1 (e.g. tonnes, km), "
                      "or smaller velocities")


def _check_inverses(world: World) -> None:
    """Inverse masses and inertias are finite (a mass or inertia near float64's smallest is not)."""
    for i, body in enumerate(world.scene.bodies):
        if not (np.isfinite(world.inv_mass[i]) and np.isfinite(world.inv_inertia_body[i]).all()):
            raise _overflow(body.where, "the inverse mass or inertia",
                            "give mass and inertia in a smaller unit, so that they are nearer 1")


def _check_totals(scene, totals, when: str) -> None:
    for name, value in zip(("kinetic energy", "momentum", "angular momentum"), totals):
        if not np.isfinite(value).all():
            raise _overflow(scene.where, f"the {name} {when}")


def _check_state(world: World, when: str | int, dt: float | None = None) -> None:
    """Every body's position, orientation and velocities are finite, else one RangeError naming
    the first body and quantity that overflowed (a huge dt or velocity does this); ``when`` is a
    phrase, or the step number (its message is only formatted on failure)."""
    # One scalar per step: a sum is finite when every term is (a sum that overflows although
    # its terms do not only costs the search below, which then finds nothing).
    if math.isfinite(world.com.sum() + world.quat.sum() + world.vel.sum() + world.omega.sum()):
        return
    arrays = (("position", world.com), ("rotation", world.quat), ("velocity", world.vel),
              ("angular_velocity", world.omega))
    for name, values in arrays:
        bad = ~np.isfinite(values).all(axis=1)
        if bad.any():
            body = world.scene.bodies[int(np.argmax(bad))]
            if isinstance(when, int):
                when = f"at step {when} (t = {when * (dt or 0.0):g})"
            raise _overflow(body.where, f"the {name} {when}", "take a smaller dt" if dt is not None else "")


def trajectory_row(t: float, body: BodyState) -> list:
    """One trajectory row (``TRAJECTORY_HEADER``) of a body; x, y, z is its centre of mass."""
    com = body.center_of_mass if body.center_of_mass is not None else body.position
    return [t, body.name, *com.tolist(), *body.rotation.tolist(), *body.velocity.tolist(),
            *body.angular_velocity.tolist()]


def _length_scale(scene) -> float:
    scale = 1.0
    for c in scene.constraints:
        scale = max(scale, float(np.abs(c.attach_a).max()), float(np.abs(c.attach_b).max()))
    return scale


def _bodies(world: World) -> tuple:
    origins = world.origins()
    out = []
    for i, body in enumerate(world.scene.bodies):
        out.append(BodyState(body.name, body.fixed, origins[i].copy(), world.quat[i].copy(),
                             world.com[i].copy() if world.known[i] else None, world.vel[i].copy(),
                             world.omega[i].copy(), bool(world.constrained[i])))
    return tuple(out)


def _result(world: World, solution, before, steps: int, time: float, worst: float) -> SolveResult:
    geos = world.geometries()
    blocks = world._blocks(geos)
    velocity = world.velocity_residuals(geos, blocks)
    position = world.position_residuals(geos)
    constraints = []
    for k, spec in enumerate(world.scene.constraints):
        report = world.modules[k].impulse(geos[k], solution.multipliers[k])
        if not all(np.isfinite(report[key]).all() for key in ("impulse", "angular_impulse") if key in report
                   and report[key] is not None):
            raise _overflow(spec.where or world.scene.where, "the impulse")
        constraints.append(ConstraintOutcome(spec.type, spec.a, spec.b, report["impulse"],
                                             report.get("angular_impulse"),
                                             float(np.linalg.norm(velocity[k])),
                                             float(np.linalg.norm(position[k])), world.island_of[k]))
    after = (world.kinetic_energy(), world.momentum(), world.angular_momentum())
    _check_totals(world.scene, after, "after the solve")
    return SolveResult(_bodies(world), tuple(constraints), solution.rank, solution.equations,
                       len(world.islands), (before[0], after[0]), (before[1], after[1]),
                       (before[2], after[2]), steps, time, worst)
