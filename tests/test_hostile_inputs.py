"""Hostile input outside the mesh readers: scenes, specs, angles, tessellations.

Each case ends in a right result or one ``p3d: error:`` line with status 2: never status 3, a
hang, a signal, or a silently wrong number.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from p3d_cli.cli.main import cli

BASE = "bodies:\n  a: {mass: 1, inertia: [1, 1, 1]}\n  b: {mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}\n"


def run(*args):
    return CliRunner().invoke(cli, [str(a) for a in args])


def one_error_line(result, *parts):
    assert result.exit_code == 2, result.output
    lines = result.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("p3d: error: "), result.stderr
    for part in parts:
        assert part in lines[0], lines[0]


@pytest.mark.parametrize("text, parts", [
    ("bodies: " + "[" * 5000 + "]" * 5000 + "\n", ["nests lists or mappings too deeply"]),
    ("bodies:\n  a: {mass: 1" + "0" * 400 + ", inertia: [1, 1, 1]}\n", ["bodies.a.mass", "too large for a float64"]),
    ("bodies:\n  a: {mass: 1, inertia: [1, 1, 1], position: [1" + "0" * 400 + ", 0, 0]}\n",
     ["bodies.a.position", "too large"]),
    (BASE + "constraints:\n  - {type: [ball], a: a, b: b, attach_a: [0, 0, 0], attach_b: [0, 0, 0]}\n",
     ["constraints[0].type", "expected a type name, got a list of 1"]),
    ("bodies:\n  a: {mass: 1e300, inertia: [1, 1, 1]}\n", ["bodies.a.mass", "write it with a dot"]),
    ("bodies:\n  a: {mass: 1, mass: 2, inertia: [1, 1, 1]}\n", ["key 'mass' appears twice"]),
])
def test_hostile_scenes_are_one_error_line(tmp_path, text, parts):
    scene = tmp_path / "scene.yaml"
    scene.write_text(text)
    one_error_line(run("solve", scene), *parts)


def test_a_merge_key_may_be_overridden(tmp_path):
    scene = tmp_path / "scene.yaml"
    scene.write_text("bodies:\n  a: &d {mass: 1, inertia: [1, 1, 1]}\n"
                     "  b: {<<: *d, mass: 2, position: [1, 0, 0], velocity: [1, 0, 0]}\n")
    result = run("solve", scene, "--json")
    assert result.exit_code == 0, result.output
    # b alone moves, with mass 2: its momentum tells the mass the merge gave way to.
    assert json.loads(result.stdout)["momentum"]["before"] == [2.0, 0.0, 0.0]


def test_devices_and_fifos_as_scenes_do_not_hang(tmp_path):
    one_error_line(run("solve", "/dev/zero"), "larger than 16 MB")
    fifo = tmp_path / "scene.yaml"
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "p3d_cli", "solve", str(fifo)], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 2 and done.stderr.startswith("p3d: error: ")


@pytest.mark.parametrize("degrees", [1e20, 1e308, -1e20, 7.5e15, 123456789.125])
def test_huge_angles_are_reduced_exactly(degrees):
    rotation = p3d.rotation_from_axis_degrees("x", degrees)
    reduced = math.fmod(degrees, 360.0)  # exact for every float
    expected = p3d.rotation_from_axis_degrees("x", reduced)
    assert np.array_equal(rotation, expected)
    c, s = math.cos(math.radians(reduced)), math.sin(math.radians(reduced))
    assert np.allclose(rotation[1:, 1:], [[c, -s], [s, c]], atol=1e-15)
    assert not np.array_equal(rotation, np.eye(3)) or reduced == 0.0


def test_a_huge_angle_is_not_the_identity_from_the_command_line():
    record = json.loads(run("props", "box", "--rotate", "x:1e20", "--json").stdout)
    assert record["placement"]["rotation"][2][1] == pytest.approx(math.sin(math.radians(280.0)), abs=1e-15)


def test_spec_underflow_says_so():
    one_error_line(run("props", "box:1e-5000,1,1"), "underflows to 0")
    one_error_line(run("props", "box:0,1,1"), "is not positive")


def test_tessellation_is_capped_before_memory_is_asked_for():
    one_error_line(run("props", "sphere", "--tessellate", "20000"), "--tessellate", "over the limit")
    one_error_line(run("bounds", "cylinder", "--tessellate", "100000000"), "--tessellate", "over the limit")
    assert run("props", "cylinder", "--tessellate", "100000", "--field", "faces").stdout.strip() == "400000"


@pytest.mark.parametrize("args, what", [
    (["box:1e200,1,1", "--json"], "overflow"),
    (["sphere:1e150"], "overflow"),
    (["box", "--scale", "1e308,1,1"], "overflow"),
    (["box", "--density", "1e308", "--json"], "the mass overflows"),
    (["box", "--translate", "1e308,0,0", "--json"], "the inertia about the origin overflows"),
    (["box", "--about", "1e308,0,0"], "the inertia about the point given overflows"),
    (["box", "--mass", "1e-320"], "below float64's normal range"),
    (["sphere:1e-110"], "underflow"),
    (["box:1e-200,1,1"], "underflow"),
    (["box", "--scale", "1e-200,1,1"], "underflow"),
])
def test_out_of_range_results_are_one_error_not_a_bug(args, what):
    with np.errstate(all="warn"):
        result = run("props", *args)
    one_error_line(result, what)
    assert "RuntimeWarning" not in result.stderr and "internal error" not in result.output


def test_large_but_representable_parts_still_measure():
    assert float(run("props", "box:1e100,1,1", "--field", "volume").stdout) == 8e100
    assert float(run("props", "box:1e-100,1,1", "--field", "volume").stdout) == 8e-100
