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

from helpers.cli import run
import p3d_cli as p3d

BASE = "bodies:\n  a: {mass: 1, inertia: [1, 1, 1]}\n  b: {mass: 1, inertia: [1, 1, 1], position: [1, 0, 0]}\n"


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
    (BASE + "constraints:\n  - {type: ball, a: [0, 0, 1], b: b, attach_a: [0, 0, 0]}\n",
     ["constraints[0].a", "expected a body name, got a list of 3"]),
    (BASE + "constraints:\n  - {type: ball, a: a, b: {x: 1}, attach_a: [0, 0, 0]}\n",
     ["constraints[0].b", "expected a body name, got a mapping"]),
    ("bodies:\n  a: {mass: '1e300', inertia: [1, 1, 1]}\n", ["bodies.a.mass", "remove the quotes"]),
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


# --- limits checked before work, and overflow found during a solve (issue 17) ---------------

PENDULUM = ("gravity: [0, 0, -9.81]\nbodies:\n  base: {fixed: true}\n"
            "  bob: {mass: 1, inertia: [0.01, 0.01, 0.01], position: [1, 0, 0]}\n"
            "constraints:\n  - {type: ball, a: base, b: bob, attach_a: [0, 0, 0], attach_b: [-1, 0, 0]}\n")


def scene_file(tmp_path, text=PENDULUM):
    path = tmp_path / "scene.yaml"
    path.write_text(text)
    return path


def bob_scene(bob: str, extra: str = "") -> str:
    return ("bodies:\n  base: {fixed: true}\n  bob: {" + bob + ", position: [1, 0, 0]}\n"
            "constraints:\n  - {type: ball, a: base, b: bob, attach_a: [0, 0, 0], attach_b: [-1, 0, 0]}\n" + extra)


def clean_error(result, *parts):
    """One error line, and no numpy warning or non-number on the way to it."""
    one_error_line(result, *parts)
    assert "RuntimeWarning" not in result.stderr and "nan" not in result.stdout.lower()


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_samples_over_the_limit_are_refused_before_the_input_is_read():
    from p3d_cli.errors import UsageError
    from p3d_cli.measure.montecarlo import MAX_SAMPLES

    clean_error(run("props", "no-such-file.stl", "--method", "montecarlo", "--samples", "10000000000000"),
                "--samples", "over the limit of 100,000,000 samples")
    with pytest.raises(UsageError) as caught:
        p3d.props("box", method="montecarlo", samples=MAX_SAMPLES + 1)
    assert caught.value.where == "samples" and "--" not in caught.value.message


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_a_tiny_tolerance_is_exact_for_a_full_box_and_capped_with_a_warning_otherwise(monkeypatch):
    import p3d_cli.measure.montecarlo as mc

    # Every sample of a box is inside: the indicator's variance is 0, so no tolerance needs more
    # than the points that give standard errors (main divided 0 by 0 here).
    full = p3d.props("box", method="montecarlo", tolerance=1e-300)
    assert full.properties.volume == 8.0 and full.details["samples"] == math.ceil(1.25 * mc.MIN_INSIDE)
    monkeypatch.setattr(mc, "MAX_SAMPLES", 30_000)
    for tolerance in (1e-300, 5e-324):
        capped = p3d.props("sphere", method="montecarlo", tolerance=tolerance)
        assert capped.details["samples"] == 30_000
        assert any("needs more than the cap of 30000" in w for w in capped.warnings)
        assert abs(capped.properties.volume - 4 / 3 * math.pi) < 5 * capped.uncertainty["volume"]


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_monte_carlo_errors_of_a_huge_mass_are_finite_and_a_huge_box_is_an_error():
    record = json.loads(run("props", "box", "--method", "montecarlo", "--samples", "5000", "--mass", "1e308",
                            "--json").stdout)
    assert record["mass"] == 1e308
    assert all(math.isfinite(v) for row in record["uncertainty"]["inertia"] for v in row)
    # The errors scale with the mass exactly (they are differentiated at unit mass).
    unit = p3d.props("sphere", method="montecarlo", samples=5000, mass=1.0).uncertainty["inertia"]
    big = p3d.props("sphere", method="montecarlo", samples=5000, mass=1e300).uncertainty["inertia"]
    np.testing.assert_allclose(big, unit * 1e300, rtol=1e-12)
    clean_error(run("props", "sphere", "--method", "montecarlo", "--scale", "1e308,1,1", "--json"),
                "bounding box overflows float64")


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("steps, parts", [
    ("100000000000000000000", ["--steps", "over the limit of 10,000,000 steps"]),
    ("10000001", ["--steps", "over the limit of 10,000,000 steps"]),
    ("1e20", ["--steps", "not a valid integer"]),
])
def test_steps_over_the_limit_are_refused_before_the_scene_is_read(steps, parts):
    clean_error(run("solve", "no-such-scene.yaml", "--steps", steps, "--dt", "0.001"), *parts)


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_steps_times_scene_size_has_a_limit(tmp_path):
    from p3d_cli.constraints import load_scene, solve_scene
    from p3d_cli.constraints.simulation import MAX_STEP_WORK, MAX_STEPS
    from p3d_cli.errors import UsageError

    bodies = "".join(f"  b{i}: {{mass: 1, inertia: [1, 1, 1], position: [{i}, 0, 0]}}\n" for i in range(30))
    path = scene_file(tmp_path, "bodies:\n" + bodies)
    assert 30 * MAX_STEPS > MAX_STEP_WORK    # the case below is within MAX_STEPS, over the work limit
    clean_error(run("solve", path, "--steps", MAX_STEPS, "--dt", "0.001"), "--steps",
                "30 bodies and 0 constraints", f"give at most {MAX_STEP_WORK // 30} steps")
    with pytest.raises(UsageError) as caught:
        solve_scene(load_scene(str(path)), steps=10 ** 20, dt=1.0)
    assert caught.value.where == "steps"
    with pytest.raises(UsageError) as caught:
        solve_scene(load_scene(str(path)), steps=1, dt=math.inf)
    assert caught.value.where == "dt"


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("dt, parts", [
    ("1e300", ["bodies.bob: the position at step 1 (t = 1e+300) overflows", "take a smaller dt"]),
    ("1e200", ["bodies.bob: the position at step 1", "overflows"]),
    ("1e100", ["the constraint system", "overflows"]),
])
def test_a_huge_time_step_is_one_error_not_nan_states(tmp_path, dt, parts):
    trajectory = tmp_path / "t.csv"
    result = run("solve", scene_file(tmp_path), "--steps", "10", "--dt", dt, "--trajectory", trajectory)
    clean_error(result, *parts)
    assert not trajectory.exists() or "nan" not in trajectory.read_text().lower()


def test_a_large_but_finite_time_step_still_steps(tmp_path):
    free = "bodies:\n  stone: {mass: 1, inertia: [1, 1, 1]}\ngravity: [0, 0, -1]\n"
    record = json.loads(run("solve", scene_file(tmp_path, free), "--steps", "2", "--dt", "1e100", "--json").stdout)
    # Velocity Verlet is exact under constant gravity: v = -g t, z = -g t² / 2.
    assert record["bodies"]["stone"]["velocity"] == [0.0, 0.0, -2e100]
    assert record["bodies"]["stone"]["position"][2] == pytest.approx(-0.5 * (2e100) ** 2, rel=1e-15)


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("bob, parts", [
    ("mass: 1.0e+300, inertia: [1.0e+300, 1.0e+300, 1.0e+300], velocity: [0, 1.0e+300, 0]",
     ["the kinetic energy before the solve overflows float64"]),
    ("mass: 1.0e+150, inertia: [1, 1, 1], velocity: [0, 1.0e+160, 0]",
     ["the kinetic energy before the solve overflows"]),
    ("mass: 1, inertia: [1, 1, 1], angular_velocity: [0, 0, 1.0e+155]", ["the kinetic energy", "overflows"]),
    ("mass: 1.0e-320, inertia: [1, 1, 1], velocity: [0, 1, 0]",
     ["bodies.bob.mass", "below float64's normal range"]),
    ("shape: box, density: 1.0e-320, velocity: [0, 1, 0]", ["bodies.bob.density", "below float64's normal range"]),
    ("mass: 1, inertia: [1.0e-320, 1.0e-320, 1.0e-320], velocity: [0, 1, 0]",
     ["bodies.bob.inertia", "below float64's normal range"]),
    ("shape: 'sphere:1e-120', velocity: [0, 1, 0]", ["bodies.bob.shape: 'sphere:1e-120'", "underflow"]),
    ("shape: 'box:1e308,0.02,1', velocity: [0, 1, 0]", ["bodies.bob.shape: 'box:1e308,0.02,1'", "overflow"]),
    ("shape: 'box:1e-110,1,1', velocity: [0, 1, 0]", ["underflow"]),
])
def test_overflow_in_a_scene_is_one_error_naming_it(tmp_path, bob, parts):
    for extra in ([], ["--steps", "3", "--dt", "0.01"]):
        result = run("solve", scene_file(tmp_path, bob_scene(bob)), *extra)
        clean_error(result, *parts)
        assert "wound inward" not in result.stderr


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_far_apart_joints_are_one_error(tmp_path):
    far = ("bodies:\n  a: {fixed: true, position: [-1.0e+308, 0, 0]}\n"
           "  b: {mass: 1, inertia: [1, 1, 1], position: [1.0e+308, 0, 0]}\nconstraints:\n")
    bar = "  - {type: bar, a: a, b: b, attach_a: [0, 0, 0], attach_b: [0, 0, 0]}\n"
    ball = "  - {type: ball, a: a, b: b, attach_a: [0, 0, 0]}\n"
    clean_error(run("solve", scene_file(tmp_path, far + bar)), "constraints[0]", "overflows float64")
    clean_error(run("solve", scene_file(tmp_path, far + ball)), "constraints[0].attach_b", "overflows float64")


@pytest.mark.filterwarnings("error::RuntimeWarning")
@pytest.mark.parametrize("args", [
    ["box:1e200,1,1"], ["sphere:1e150"], ["sphere:1e-110"], ["box:1e-200,1,1"], ["torus:1e100,1e99"],
    ["box", "--scale", "1e308,1,1"], ["box", "--scale", "1e-200,1,1"], ["box", "--density", "1e308"],
    ["box", "--density", "1e-320"], ["box", "--mass", "1e308"], ["box", "--translate", "1e308,0,0"],
    ["box", "--about", "1e308,0,0"], ["box", "--about", "1e160,0,0"], ["sphere", "--rotate", "x:1e308"],
])
@pytest.mark.parametrize("method", [[], ["--method", "montecarlo", "--samples", "3000"]])
def test_hostile_props_are_a_right_result_or_one_error_without_numpy_warnings(args, method):
    result = run("props", *args, *method, "--json")
    assert result.exit_code in (0, 2), result.output
    assert "RuntimeWarning" not in result.stderr
    if result.exit_code == 2:
        one_error_line(result)
    else:
        assert "NaN" not in result.stdout and "Infinity" not in result.stdout


@pytest.mark.filterwarnings("error::RuntimeWarning")
def test_extreme_but_valid_scene_values_are_read_without_overflow(tmp_path):
    from p3d_cli.constraints import values
    from p3d_cli.errors import SceneError

    np.testing.assert_array_equal(values.inertia([1e308, 1e308, 1e308], "i"), np.diag([1e308] * 3))
    with pytest.raises(SceneError, match="triangle inequality"):
        values.inertia([1e308, 1e307, 1e306], "i")
    s = math.sqrt(0.5)
    for q in ([1e200, 1e200, 0, 0], [1e-300, 1e-300, 0, 0]):
        np.testing.assert_allclose(values.rotation({"quat": q}, "r"), [s, s, 0, 0], rtol=1e-15)
    # A hinge axis written at any scale is the same axis: the solve is the same as with [0, 0, 1].
    hinge = ("bodies:\n  base: {fixed: true}\n  door: {mass: 1, inertia: [1, 1, 1], position: [1, 0, 0],"
             " angular_velocity: [1, 2, 3]}\nconstraints:\n  - {type: hinge, a: base, b: door, attach_a: [0, 0, 0],"
             " axis_a: [0, 0, AXIS], axis_b: [0, 0, 1]}\n")
    records = [json.loads(run("solve", scene_file(tmp_path, hinge.replace("AXIS", a)), "--json").stdout)
               for a in ("1", "1.0e+200", "1.0e-300")]
    omega = records[0]["bodies"]["door"]["angular_velocity"]
    assert omega[:2] == [0.0, 0.0] and omega[2] > 0     # only the turn about the hinge is left
    assert records[1] == records[0] and records[2] == records[0]


def test_the_step_limits_in_the_help_are_the_ones_enforced():
    from p3d_cli.constraints.simulation import MAX_STEP_WORK, MAX_STEPS

    text = " ".join(run("solve", "--help").stdout.split())
    assert f"at most {MAX_STEPS:,}, and {MAX_STEP_WORK:,} / (bodies + constraints)" in text
