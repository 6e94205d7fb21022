"""``p3d solve --plot/--animate``: one stepped solve whose motion is kept, then its pictures."""

from __future__ import annotations

import contextlib
import os


def solve_with_pictures(path: str, scene, steps: int, dt: float, trajectory: str | None, plot: str | None,
                        animate: str | None):
    """Step ``scene`` once (writing ``trajectory`` too), write the plot and the animation, and
    return the ``SolveResult``."""
    from p3d_cli.constraints.motion import record_motion
    from p3d_cli.constraints.trajectory import trajectory_writer
    from p3d_cli.render.motion import _pyplot, body_triangles, check_picture_paths, write_animation, write_plot

    check_picture_paths(plot, animate, inputs=[path])   # what the paths cannot be, then
    _pyplot("--plot" if plot else "--animate")          # the extra's absence, said before the work
    with (trajectory_writer(trajectory) if trajectory else contextlib.nullcontext()) as record:
        result, motion = record_motion(scene, steps=steps, dt=dt, on_step=record)
    if plot:
        write_plot(motion, plot, title=os.path.basename(path), inputs=[path])
    if animate:
        write_animation(motion, body_triangles(scene), animate,
                        inputs=[path], scene=scene)
    return result
