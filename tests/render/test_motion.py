"""``p3d solve --plot/--animate`` and the motion they draw: energy, joint errors, files as asked."""

from __future__ import annotations

import builtins
import shutil

import numpy as np
import pytest
from helpers.cli import run
from helpers.real_meshes import REPO

import p3d_cli as p3d
from p3d_cli.constraints.motion import record_motion
from p3d_cli.render.png import decode_png

PENDULUM = REPO / "examples" / "pendulum.yaml"


def test_a_pendulum_keeps_its_energy_and_its_bar(tmp_path):
    scene = p3d.load_scene(str(PENDULUM))
    result, motion = record_motion(scene, steps=400, dt=0.002, samples=100)
    assert motion.time[0] == 0 and np.isclose(motion.time[-1], 0.8) and motion.every == 4
    assert len(motion.time) == 101
    # After the first velocity solve (t = 0 is the state as written, with its push along the
    # bar), RATTLE keeps the energy to a few parts in 10^5 and the bar's length exactly.
    energy = motion.energy[1:]
    assert np.ptp(energy) <= 1e-4 * abs(energy).max()
    assert motion.joint_errors[1:].max() <= 1e-9
    bob = motion.bodies.index("bob")
    assert np.allclose(np.linalg.norm(motion.position[:, bob], axis=1)[1:], 1.0, atol=1e-9)
    assert np.allclose(motion.position[-1, bob], result.bodies[bob].center_of_mass)


def test_plot_and_animation_files(tmp_path):
    image_module = pytest.importorskip("PIL.Image")
    plot, gif = tmp_path / "swing.png", tmp_path / "swing.gif"
    result = run("solve", PENDULUM, "--steps", "40", "--dt", "0.02", "--plot", plot, "--animate", gif)
    assert result.exit_code == 0, result.output
    assert decode_png(plot.read_bytes()).shape[:2] == (750, 1000)
    with image_module.open(gif) as animation:
        assert animation.n_frames == 41 and animation.size == (480, 360)


def test_mp4_without_ffmpeg_says_so(tmp_path):
    if shutil.which("ffmpeg"):
        pytest.skip("ffmpeg is installed")
    result = run("solve", PENDULUM, "--steps", "10", "--dt", "0.01", "--animate", tmp_path / "a.mp4")
    assert result.exit_code == 2 and "ffmpeg" in result.output
    assert len(result.output.strip().splitlines()) == 1 and not (tmp_path / "a.mp4").exists()


def test_pictures_need_steps_and_known_formats(tmp_path):
    result = run("solve", PENDULUM, "--plot", tmp_path / "p.png")
    assert result.exit_code == 2 and "--plot" in result.output and "--steps" in result.output
    result = run("solve", PENDULUM, "--steps", "10", "--dt", "0.01", "--plot", tmp_path / "p.bmp")
    assert result.exit_code == 2 and ".png" in result.output


def test_without_matplotlib_the_extra_is_named(tmp_path, monkeypatch):
    real_import = builtins.__import__

    def no_matplotlib(name, *args, **kwargs):
        if name == "matplotlib" or name.startswith("matplotlib."):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    result = run("solve", PENDULUM, "--steps", "10", "--dt", "0.01", "--plot", tmp_path / "p.png")
    assert result.exit_code == 2
    assert "extra 'render'" in result.output and len(result.output.strip().splitlines()) == 1
