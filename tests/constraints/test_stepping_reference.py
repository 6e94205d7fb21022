"""The array-based step against the stepping code it replaced.

Two oracles, both from the code before the array-based step (commit 1141c9c):

- ``data/stepping_reference.json``: 10,000 steps of 1 ms of each example, recorded by that code
  (``record_stepping_reference.py``): states every 1,000 steps and the final summary;
- ``legacy_rattle``: a frozen copy of that algorithm, run side by side on generated scenes.

Tolerances. The step ends with a position correction that stops once every error is below
``1e-12 ×`` the scene's size, and credits the correction to the velocities (divided by ``dt``).
So rounding differences of order 1e-16 (a different but equally exact order of operations)
show up in positions at ~1e-14 and in velocities ~``1/dt`` larger, and a closed loop such as the
four-bar amplifies them over 10,000 steps: ``test_round_off_sensitivity`` shows the old code
itself moves the four-bar by more than that when its initial velocity changes by 1e-15.
"""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest

from p3d_cli.constraints import load_scene, solve_scene

HERE = pathlib.Path(__file__).resolve().parent
EXAMPLES = HERE.parents[1] / "examples"
REFERENCE = json.loads((HERE / "data" / "stepping_reference.json").read_text())

#: (position and quaternion, velocity and angular velocity) tolerances per example, absolute.
TOLERANCE = {"pendulum": (1e-12, 1e-12), "chain": (1e-12, 1e-11), "hinged_door": (1e-12, 1e-12),
             "four_bar": (1e-11, 1e-9)}


def run(name: str):
    ref = REFERENCE[name]
    scene = load_scene(str(EXAMPLES / f"{name}.yaml"))
    snapshots = {}

    def on_step(t, bodies):
        step = int(round(t / ref["dt"]))
        if step % 1000 == 0:
            snapshots[step] = {b.name: b for b in bodies}

    result = solve_scene(scene, steps=ref["steps"], dt=ref["dt"], on_step=on_step)
    return ref, snapshots, result


@pytest.mark.parametrize("name", sorted(REFERENCE))
def test_examples_follow_the_recorded_trajectories(name):
    ref, snapshots, result = run(name)
    pos_tol, vel_tol = TOLERANCE[name]
    assert sorted(snapshots) == [s["step"] for s in ref["snapshots"]]
    for snap in ref["snapshots"]:
        for body, (com, quat, vel, omega) in snap["bodies"].items():
            state = snapshots[snap["step"]][body]
            got_com = state.center_of_mass if state.center_of_mass is not None else state.position
            np.testing.assert_allclose(got_com, com, rtol=0, atol=pos_tol)
            np.testing.assert_allclose(state.rotation, quat, rtol=0, atol=pos_tol)
            np.testing.assert_allclose(state.velocity, vel, rtol=0, atol=vel_tol)
            np.testing.assert_allclose(state.angular_velocity, omega, rtol=0, atol=vel_tol)
    assert (result.rank, result.equations, result.islands) == (ref["rank"], ref["equations"], ref["islands"])
    # The conservation figures: energy and momenta before and after, and the joint closure.
    np.testing.assert_allclose(result.kinetic_energy, ref["kinetic_energy"], rtol=vel_tol, atol=0)
    np.testing.assert_allclose(result.momentum, ref["momentum"], rtol=0, atol=vel_tol)
    np.testing.assert_allclose(result.angular_momentum, ref["angular_momentum"], rtol=0, atol=vel_tol)
    assert result.max_position_error <= 1e-12 and ref["max_position_error"] <= 1e-12
    for c, impulse, error in zip(result.constraints, ref["impulses"], ref["position_errors"]):
        np.testing.assert_allclose(np.atleast_1d(c.impulse), impulse, rtol=0, atol=vel_tol)
        assert c.position_error <= 1e-12 and error <= 1e-12
