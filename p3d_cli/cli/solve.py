"""``p3d solve``: constraint impulses (and optionally motion in time) of a YAML scene."""

from __future__ import annotations

import click

from p3d_cli.cli import output
from p3d_cli.cli.options import FiniteFloat, json_option
from p3d_cli.constraints import SolveResult, load_scene, solve_scene
from p3d_cli.constraints.outcome import solve_record
from p3d_cli.constraints.simulation import check_steps
from p3d_cli.constraints.trajectory import trajectory_writer
from p3d_cli.errors import UsageError


@click.command()
@click.argument("scene", metavar="SCENE.yaml")
@click.option("--steps", type=click.IntRange(min=0), default=0, show_default=True,
              help="Advance the scene this many time steps under its gravity (0: one velocity solve; "
                   "at most 10,000,000, and 100,000,000 / (bodies + constraints): docs/solve.md).")
@click.option("--dt", type=FiniteFloat(positive=True), default=None, metavar="SECONDS",
              help="Time step for --steps.")
@click.option("--trajectory", type=click.Path(dir_okay=False, writable=True), default=None, metavar="FILE.csv",
              help="Write one CSV row per body per step: t,body,x,y,z,qw,qx,qy,qz,vx,vy,vz,wx,wy,wz "
                   "(x, y, z: the centre of mass).")
@click.option("--plot", type=click.Path(dir_okay=False), default=None, metavar="FILE.png|svg|pdf",
              help="With --steps: plot positions, turns, joint errors and energy against time "
                   "(needs p3d's extra 'render').")
@click.option("--animate", type=click.Path(dir_okay=False), default=None, metavar="FILE.gif|mp4",
              help="With --steps: an animation of the bodies (needs p3d's extra 'render'; MP4 also ffmpeg).")
@json_option
def solve(scene, steps, dt, trajectory, plot, animate, as_json):
    """Solve ball, hinge and bar constraints between rigid bodies.

    Reads a YAML scene (bodies with shapes, meshes, parts as in an assembly file, or plain mass
    and inertia; constraints between them; see docs/solve.md), solves the constraint equations
    (eq. 20 of the Physics3D note, in world coordinates) for the impulses that make the bodies'
    motions agree, and reports the new velocities, each constraint's impulse and remaining
    error, kinetic energy and momentum before and after, and the rank of the system (redundant
    constraints are solved in the minimum-norm sense). With --steps and --dt it steps the scene
    in time under gravity.

    \b
    Examples:
      p3d solve examples/pendulum.yaml
      p3d solve examples/four_bar.yaml --json
      p3d solve examples/pendulum.yaml --steps 2000 --dt 0.001 --trajectory swing.csv
      p3d solve examples/hinged_door.yaml --steps 2000 --dt 0.001 --plot door.png --animate door.gif
    """
    if steps == 0 and (dt is not None or trajectory is not None or plot or animate):
        option = next(name for name, value in (("--dt", dt), ("--trajectory", trajectory), ("--plot", plot),
                                               ("--animate", animate)) if value is not None)
        raise UsageError(option, "only applies when stepping", "add --steps N")
    if steps > 0 and dt is None:
        raise UsageError("--dt", "stepping needs a time step", "give --dt, e.g. --dt 0.001")
    check_steps(steps, dt)  # the limits that need no scene, before reading it
    parsed = load_scene(scene)
    if plot or animate:
        from p3d_cli.cli.solve_pictures import solve_with_pictures

        result = solve_with_pictures(scene, parsed, steps, dt, trajectory, plot, animate)
    elif trajectory is None:
        result = solve_scene(parsed, steps=steps, dt=dt)
    else:
        with trajectory_writer(trajectory, inputs=[scene]) as record:
            result = solve_scene(parsed, steps=steps, dt=dt, on_step=record)
    if as_json:
        click.echo(output.formatted("solve", solve_record(result), "json"))
    else:
        click.echo(solve_table(scene, result))


def solve_table(where: str, result: SolveResult) -> str:
    """A readable summary, 80 columns wide (a long scene path or body name aside): one labelled
    line per vector."""
    num, vec = output.number, _short_vector
    n_c = len(result.constraints)
    redundancy = ("no redundancy" if result.redundant == 0 else
                  f"{result.redundant} redundant, solved in the minimum-norm sense")
    lines = [f"{where}: {len(result.bodies)} bodies, {n_c} constraint{'s' if n_c != 1 else ''}, "
             f"{result.islands} island{'s' if result.islands != 1 else ''}",
             f"  rank {result.rank} of {result.equations} equations ({redundancy})"]
    if result.steps:
        lines.append(f"stepped {result.steps} steps to t = {num(result.time)}; largest joint drift "
                     f"{num(result.max_position_error)}")
    lines.append("bodies (world frame; velocity of the centre of mass):")
    for b in result.bodies:
        state = "  fixed" if b.fixed else ("" if b.constrained else "  (free, unchanged by constraints)")
        lines.append(f"  {b.name}{state}")
        lines.append(f"    position          {vec(b.position)}")
        lines.append(f"    rotation          {vec(b.rotation)}")
        if not b.fixed:
            lines.append(f"    velocity          {vec(b.velocity)}")
            lines.append(f"    angular velocity  {vec(b.angular_velocity)}")
    if result.constraints:
        lines.append("constraints (impulse on b, world frame; error: remaining velocity error):")
        for i, c in enumerate(result.constraints):
            impulse = num(c.impulse) if isinstance(c.impulse, float) else vec(c.impulse)
            lines.append(f"  [{i}] {c.type} {c.a} -> {c.b}")
            lines.append(f"    impulse           {impulse}")
            if c.angular_impulse is not None:
                lines.append(f"    angular impulse   {vec(c.angular_impulse)}")
            lines.append(f"    error {num(c.error)}, position error {num(c.position_error)}")
    ke = result.kinetic_energy
    lines.append(f"kinetic energy: {num(ke[0])} -> {num(ke[1])}")
    lines.append("momentum:")
    lines.append(f"  before  {vec(result.momentum[0])}")
    lines.append(f"  after   {vec(result.momentum[1])}")
    lines.append("angular momentum (about the origin):")
    lines.append(f"  before  {vec(result.angular_momentum[0])}")
    lines.append(f"  after   {vec(result.angular_momentum[1])}")
    return "\n".join(lines)


def _short_vector(v) -> str:
    return "[" + ", ".join(f"{float(x) + 0.0:.6g}" for x in v) + "]"  # + 0.0: no "-0"
