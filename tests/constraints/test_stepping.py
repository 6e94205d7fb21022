"""Stepping in time: pendulum periods against theory, and joint drift over thousands of steps."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import ellipk

from p3d_cli.constraints import load_scene, parse_scene, solve_scene
from p3d_cli.constraints.rotation import quat_to_matrix

G = 9.81
EXAMPLES = __import__("pathlib").Path(__file__).resolve().parents[2] / "examples"


def exact_period(length: float, amplitude: float) -> float:
    """T = 4 √(L/g) K(k), k = sin(θ0/2) (scipy's ellipk takes the parameter m = k²)."""
    return 4 * math.sqrt(length / G) * ellipk(math.sin(amplitude / 2) ** 2)


def measured_period(scene, dt: float, duration: float, body: str) -> float:
    """Period from the swing angle's downward zero crossings (interpolated linearly)."""
    times, angles = [], []

    def record(t, bodies):
        state = next(b for b in bodies if b.name == body)
        times.append(t)
        angles.append(math.atan2(state.center_of_mass[0], -state.center_of_mass[2]))

    solve_scene(scene, steps=int(round(duration / dt)), dt=dt, on_step=record)
    t, a = np.array(times), np.array(angles)
    down = np.flatnonzero((a[:-1] > 0) & (a[1:] <= 0))
    crossings = t[down] + (t[down + 1] - t[down]) * a[down] / (a[down] - a[down + 1])
    assert len(crossings) >= 2, "the pendulum did not complete a period"
    return float(np.mean(np.diff(crossings)))


def simple_pendulum(length: float, amplitude: float):
    return parse_scene({
        "gravity": [0, 0, -G],
        "bodies": {"pivot": {"fixed": True},
                   "bob": {"mass": 1.0, "inertia": [1e-4, 1e-4, 1e-4],
                           "position": [length * math.sin(amplitude), 0, -length * math.cos(amplitude)]}},
        "constraints": [{"type": "bar", "a": "pivot", "b": "bob", "attach_a": [0, 0, 0], "attach_b": [0, 0, 0],
                         "length": length}],
    }, "pendulum", ".")


@pytest.mark.parametrize("amplitude_deg", [5.0, 90.0])
def test_simple_pendulum_period_matches_the_elliptic_integral(amplitude_deg):
    amplitude = math.radians(amplitude_deg)
    theory = exact_period(1.0, amplitude)
    measured = measured_period(simple_pendulum(1.0, amplitude), 2e-3, 2.3 * theory, "bob")
    assert measured == pytest.approx(theory, rel=1e-4)
    if amplitude_deg == 90.0:
        # The large-amplitude correction is real and captured: 18% longer than 2π√(L/g).
        small = 2 * math.pi * math.sqrt(1.0 / G)
        assert measured > 1.15 * small


def test_hinged_rod_swings_as_a_physical_pendulum():
    # A uniform 1 m, 1 kg rod hinged at one end: I_pivot = m ℓ²/3, d = ℓ/2, so L_eq = 2ℓ/3.
    length, mass, amplitude = 1.0, 1.0, math.radians(60)
    i_com = mass * length ** 2 / 12
    q = [math.cos(amplitude / 2), 0, math.sin(amplitude / 2), 0]      # rod turned about y
    rot = quat_to_matrix(np.array(q))
    centre = rot @ np.array([0, 0, -length / 2])                      # pivot at the origin
    scene = parse_scene({
        "gravity": [0, 0, -G],
        "bodies": {"wall": {"fixed": True},
                   "rod": {"mass": mass, "inertia": [i_com, i_com, 1e-3], "position": centre.tolist(),
                           "rotation": {"quat": q}}},
        "constraints": [{"type": "hinge", "a": "wall", "b": "rod", "attach_a": [0, 0, 0],
                         "attach_b": [0, 0, length / 2], "axis_a": [0, 1, 0], "axis_b": [0, 1, 0]}],
    }, "rod", ".")
    l_eq = (i_com + mass * (length / 2) ** 2) / (mass * length / 2)
    assert l_eq == pytest.approx(2 / 3)
    theory = exact_period(l_eq, amplitude)
    measured = measured_period(scene, 2e-3, 2.3 * theory, "rod")
    assert measured == pytest.approx(theory, rel=1e-4)


def test_joint_drift_stays_small_over_thousands_of_steps():
    scene = load_scene(str(EXAMPLES / "chain.yaml"))
    lengths = []

    def record(t, bodies):
        states = {b.name: b for b in bodies}
        # Joint between link2 and link3: link2's bottom and link3's top must coincide.
        two, three = states["link2"], states["link3"]
        bottom = two.position + quat_to_matrix(two.rotation) @ np.array([0, 0, -0.1])
        top = three.position + quat_to_matrix(three.rotation) @ np.array([0, 0, 0.1])
        lengths.append(float(np.linalg.norm(bottom - top)))

    result = solve_scene(scene, steps=2000, dt=2e-3, on_step=record)
    assert max(lengths) < 1e-9
    assert result.max_position_error < 1e-9
    assert max(c.position_error for c in result.constraints) < 1e-9
    # The chain really moved: it is not a trivially static test.
    assert np.linalg.norm(result.bodies[-1].position - np.array([0, 0, -0.9])) > 0.05


def test_stepping_keeps_quaternions_unit_and_energy_bounded():
    scene = load_scene(str(EXAMPLES / "four_bar.yaml"))
    result = solve_scene(scene, steps=300, dt=2e-3)
    for body in result.bodies:
        assert abs(np.linalg.norm(body.rotation) - 1) < 1e-12
    assert result.max_position_error < 1e-9
    assert np.isfinite(result.kinetic_energy[1])


def test_unlinked_body_falls_freely_under_gravity():
    scene = parse_scene({"gravity": [0, 0, -10.0],
                         "bodies": {"stone": {"mass": 1.0, "inertia": [1, 1, 1], "velocity": [1, 0, 0]}}},
                        "fall", ".")
    result = solve_scene(scene, steps=100, dt=0.01)
    stone = result.bodies[0]
    np.testing.assert_allclose(stone.velocity, [1, 0, -10.0], atol=1e-12)
    # Half kicks around the drift (velocity Verlet) are exact for constant gravity: z = -g t²/2.
    np.testing.assert_allclose(stone.position, [1.0, 0, -0.5 * 10 * 1.0 ** 2], atol=1e-12)


def test_stepping_needs_a_positive_time_step():
    from p3d_cli.errors import UsageError

    with pytest.raises(UsageError):
        solve_scene(simple_pendulum(1.0, 0.1), steps=10, dt=None)
    with pytest.raises(UsageError):
        solve_scene(simple_pendulum(1.0, 0.1), steps=10, dt=-1.0)
