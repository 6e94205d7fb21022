"""Pictures of a stepped scene: a plot of its motion (matplotlib) and an animation of its bodies.

``motion_plot``: four panels against time: each free body's centre of mass (x, y, z), its turn
from its first orientation (the rotation vector's components, degrees: a hinge's swing is the
component along its axis), each joint's position error (log scale), and the kinetic, potential
and total energy with the total's drift. ``motion_animation``: the bodies drawn by p3d's own
renderer from a fixed camera, one frame per kept state (at most ``FRAMES``), written as GIF
(through Pillow) or MP4 (through ffmpeg) by matplotlib's writers.

matplotlib is the ``render`` extra, imported only here, when a plot or an animation is asked
for; without it these raise ``MissingExtraError`` naming the extra.
"""

from __future__ import annotations

import io
import os
import shutil
import tempfile
from typing import Iterable

import numpy as np

from p3d_cli.errors import MissingExtraError, UsageError, install_hint

#: Most frames of an animation, and its frame rate.
FRAMES = 150
FPS = 25
PLOT_FORMATS = (".png", ".svg", ".pdf")
ANIMATION_FORMATS = (".gif", ".mp4")


def _pyplot(where: str):
    try:
        import matplotlib

        matplotlib.use("Agg")              # headless: no display is ever needed
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingExtraError(where, "plots need matplotlib, which is not installed",
                                install_hint("render", "'matplotlib>=3.7'")) from None
    return plt


def motion_plot(motion, title: str = "", size=(10.0, 7.5)):
    """A matplotlib ``Figure`` of ``motion`` (a ``p3d_cli.constraints.motion.Motion``)."""
    plt = _pyplot("plot")
    fig, axes = plt.subplots(2, 2, figsize=size, sharex=True, constrained_layout=True)
    t = motion.time
    free = [j for j in range(len(motion.bodies)) if not motion.fixed[j]]
    shown = free[:6]
    labels = "xyz"
    ax = axes[0, 0]
    for j in shown:
        for k in range(3):
            if np.ptp(motion.position[:, j, k]) > 0 or k == 2:
                ax.plot(t, motion.position[:, j, k], label=f"{motion.bodies[j]} {labels[k]}")
    ax.set_title("centre of mass")
    ax.set_ylabel("position")
    ax = axes[0, 1]
    turns = np.degrees(motion.turn_angles())
    for j in shown:
        for k in range(3):
            if np.ptp(turns[:, j, k]) > 1e-9:
                ax.plot(t, turns[:, j, k], label=f"{motion.bodies[j]} about {labels[k]}")
    ax.set_title("turn from the start (rotation vector)")
    ax.set_ylabel("degrees")
    ax = axes[1, 0]
    for c, name in enumerate(motion.joints):
        errors = np.where(motion.joint_errors[:, c] > 0, motion.joint_errors[:, c], np.nan)   # log: no zeros
        ax.semilogy(t, errors, label=f"[{c}] {name}")
    ax.set_title("joint position errors")
    ax.set_ylabel("error (length)")
    ax.set_xlabel("time")
    ax = axes[1, 1]
    # Changes from the start, so that a small kinetic energy is not flattened by a large
    # potential one; the title gives the totals.
    ax.plot(t, motion.kinetic - motion.kinetic[0], label="kinetic")
    ax.plot(t, motion.potential - motion.potential[0], label="potential")
    ax.plot(t, motion.energy - motion.energy[0], label="total", color="black", linewidth=1.5)
    ax.set_title(f"energy change (total {motion.energy[0]:.6g} at the start, {motion.energy[-1]:.6g} at the end)",
                 fontsize=10)
    ax.set_xlabel("time")
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
        handles, _ = ax.get_legend_handles_labels()
        if handles:
            ax.legend(fontsize=8, loc="best")
    hidden = len(free) - len(shown)
    note = f" ({hidden} more free bodies not shown)" if hidden > 0 else ""
    fig.suptitle(f"{title}{note}".strip() or "motion")
    return fig


def check_picture_paths(plot: str | None, animate: str | None, inputs: Iterable[str] = ()) -> None:
    """Refuse, before any work and before matplotlib is needed, what ``write_plot`` and
    ``write_animation`` would refuse of their paths: an unknown extension, a path that would
    replace an input, an MP4 without ffmpeg on PATH.

    Raises
    ------
    UsageError, MissingExtraError, OutputError
    """
    from p3d_cli.io.atomic import destination

    inputs = list(inputs)
    if plot:
        _plot_extension(plot)
        destination(plot, inputs=inputs, what="the plot")
    if animate:
        if _animation_extension(animate) == ".mp4" and shutil.which("ffmpeg") is None:
            raise MissingExtraError("animate", "writing MP4 needs ffmpeg on PATH, which is not available",
                                    "install ffmpeg (e.g. apt-get install ffmpeg), or write a .gif")
        destination(animate, inputs=inputs, what="the animation")


def _plot_extension(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in PLOT_FORMATS:
        raise UsageError("plot", f"{path}: cannot write a plot as {ext or 'no extension'!r}",
                         "name a .png, .svg or .pdf file")
    return ext


def _animation_extension(path: str) -> str:
    ext = os.path.splitext(path)[1].lower()
    if ext not in ANIMATION_FORMATS:
        raise UsageError("animate", f"{path}: cannot write an animation as {ext or 'no extension'!r}",
                         "name a .gif or .mp4 file")
    return ext


def write_plot(motion, path: str, *, title: str = "", inputs: Iterable[str] = ()) -> None:
    """Write ``motion_plot`` to ``path`` (.png, .svg or .pdf), whole or not at all."""
    from p3d_cli.io.atomic import write_bytes

    ext = _plot_extension(path)
    plt = _pyplot("plot")
    figure = motion_plot(motion, title)
    data = io.BytesIO()
    figure.savefig(data, format=ext[1:], dpi=100)
    plt.close(figure)
    write_bytes(path, data.getvalue(), inputs=inputs, what="the plot")


def body_triangles(scene, segments: int = 32) -> list[np.ndarray]:
    """Each body's triangles in its own frame: its shape (a mesh path as the scene resolved it
    against its folder) or parts; a body given only by its mass properties is drawn as its
    equivalent uniform box (a small cube without them)."""
    from p3d_cli.render.geometry import scene_triangles

    out = []
    for body in scene.bodies:
        thing = body.parts if body.parts is not None else (body.shape_path or body.shape)
        if thing is not None:
            out.append(np.asarray(scene_triangles(thing, segments=segments).triangles, dtype=np.float64))
            continue
        half = np.full(3, 0.05)
        if body.inertia is not None and body.mass:
            i = np.linalg.eigvalsh(np.asarray(body.inertia, dtype=np.float64))
            half = np.sqrt(np.clip(3 * (i.sum() - 2 * i) / (2 * body.mass), 1e-12, None))
        centre = np.zeros(3) if body.center_of_mass is None else np.asarray(body.center_of_mass)
        out.append(_box_triangles(centre - half, centre + half))
    return out


def _box_triangles(low, high) -> np.ndarray:
    from p3d_cli.shapes import Box

    half = 0.5 * (np.asarray(high) - np.asarray(low))
    return Box(*np.maximum(half, 1e-9)).triangles() + 0.5 * (np.asarray(high) + np.asarray(low))


def animation_frames(motion, bodies: list[np.ndarray], size=(480, 360), view="iso", frames: int = FRAMES,
                     scene=None):
    """The pictures of an animation: ``(frames, h, w, 3)`` uint8, from one fixed camera; with
    ``scene``, each constraint is drawn as a line between its two attachment points."""
    from p3d_cli.constraints.rotation import quat_to_matrix_many
    from p3d_cli.render.camera import make_camera
    from p3d_cli.render.compose import compose
    from p3d_cli.render.overlays import Layer

    index = {name: j for j, name in enumerate(motion.bodies)}
    links = [] if scene is None else [(index[c.a], np.asarray(c.attach_a, dtype=np.float64), index[c.b],
                                       np.asarray(c.attach_b, dtype=np.float64)) for c in scene.constraints]

    picks = np.unique(np.linspace(0, len(motion.time) - 1, min(frames, len(motion.time))).round().astype(int))
    placed = []
    for i in picks:
        rot = quat_to_matrix_many(motion.rotation[i])
        parts = [tri @ rot[j].T + motion.origin[i, j] for j, tri in enumerate(bodies)]
        placed.append(np.concatenate(parts) if parts else np.zeros((0, 3, 3)))
    everywhere = np.concatenate([p.reshape(-1, 3) for p in placed])
    camera = make_camera(view)
    out = []
    for i, triangles in zip(picks, placed):
        layers = []
        if links:
            rot = quat_to_matrix_many(motion.rotation[i])
            ends = [[motion.origin[i, a] + rot[a] @ pa, motion.origin[i, b] + rot[b] @ pb] for a, pa, b, pb in links]
            layers.append(Layer("joint", "joints (attachment points)", segments=np.array(ends)))
        picture = compose(triangles, camera, size, layers, f"t = {motion.time[i]:.3f}", f"{view} view",
                          fit_points=everywhere)
        out.append(picture.pixels)
    return np.array(out)


def write_animation(motion, bodies: list[np.ndarray], path: str, *, inputs: Iterable[str] = (),
                    size=(480, 360), view: str = "iso", scene=None) -> None:
    """Write the frames of ``animation_frames`` as a GIF or MP4, whole or not at all.

    Raises
    ------
    UsageError, MissingExtraError, OutputError
    """
    from p3d_cli.io.atomic import destination, write_bytes

    ext = _animation_extension(path)
    destination(path, inputs=inputs, what="the animation")          # refuse before the work
    plt = _pyplot("animate")
    from matplotlib import animation

    writer_name = "pillow" if ext == ".gif" else "ffmpeg"
    if not animation.writers.is_available(writer_name):
        need = "Pillow" if ext == ".gif" else "ffmpeg on PATH"
        raise MissingExtraError("animate", f"writing {ext[1:].upper()} needs {need}, which is not available",
                                "install ffmpeg (e.g. apt-get install ffmpeg), or write a .gif" if ext == ".mp4"
                                else install_hint("render", "'matplotlib>=3.7'"))
    frames = animation_frames(motion, bodies, size, view, scene=scene)
    h, w = frames.shape[1:3]
    figure = plt.figure(figsize=(w / 100, h / 100), dpi=100)
    axes = figure.add_axes((0, 0, 1, 1))
    axes.set_axis_off()
    image = axes.imshow(frames[0], interpolation="nearest")
    writer = animation.writers[writer_name](fps=FPS)
    with tempfile.TemporaryDirectory() as folder:
        temporary = os.path.join(folder, "animation" + ext)
        with writer.saving(figure, temporary, dpi=100):
            for frame in frames:
                image.set_data(frame)
                writer.grab_frame()
        plt.close(figure)
        with open(temporary, "rb") as f:
            data = f.read()
    write_bytes(path, data, inputs=inputs, what="the animation")
