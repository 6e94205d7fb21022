"""The small-scene step (``small_step``, floats) against the array step (``World``) it stands for.

Both are the same RATTLE step; they differ only in the order of some sums, so on generated
scenes they agree to rounding (amplified by ``1/dt`` in the velocities, as in
``test_stepping_reference``). The float kernels (``scalar``) are checked one by one against
the numpy functions they restate, and the rank certificate of ``small_step`` against the
eigenvalue rule of ``solver``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.joints import make_joint
from hypothesis import given, settings, strategies as st
from test_constraint_solver import scenes, unit_quats

from p3d_cli.constraints import parse_scene, scalar, small_step, solve_scene
from p3d_cli.constraints.hinge import frames as hinge_frames
from p3d_cli.constraints.rotation import quat_to_matrix, rotate_by_many
from p3d_cli.constraints.solver import RANK_RTOL
from p3d_cli.errors import RangeError, SceneError


def both_paths(scene, **kw):
    """(small-step result, array-step result, whether the small step was taken) of one solve."""
    taken = []
    real = small_step.fits

    def spy(world):
        taken.append(real(world))
        return taken[-1]

    with pytest.MonkeyPatch.context() as m:
        m.setattr(small_step, "fits", spy)
        fast = solve_scene(scene, **kw)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(small_step, "fits", lambda world: False)
        slow = solve_scene(scene, **kw)
    return fast, slow, bool(taken and taken[0])


def assert_same(fast, slow, pos_tol: float, vel_tol: float) -> None:
    assert (fast.rank, fast.equations, fast.islands) == (slow.rank, slow.equations, slow.islands)
    for a, b in zip(fast.bodies, slow.bodies):
        assert a.name == b.name
        np.testing.assert_allclose(a.position, b.position, rtol=0, atol=pos_tol)
        np.testing.assert_allclose(a.rotation, b.rotation, rtol=0, atol=pos_tol)
        np.testing.assert_allclose(a.velocity, b.velocity, rtol=0, atol=vel_tol)
        np.testing.assert_allclose(a.angular_velocity, b.angular_velocity, rtol=0, atol=vel_tol)
    for a, b in zip(fast.constraints, slow.constraints):
        np.testing.assert_allclose(np.atleast_1d(a.impulse), np.atleast_1d(b.impulse), rtol=1e-6, atol=vel_tol)
    assert fast.max_position_error == pytest.approx(slow.max_position_error, rel=0, abs=pos_tol)
    np.testing.assert_allclose(fast.kinetic_energy, slow.kinetic_energy, rtol=vel_tol, atol=vel_tol)


@settings(max_examples=40, deadline=None)
@given(scenes(), st.booleans())
def test_generated_scenes_step_alike_on_both_paths(data, diagonal):
    # Full inertia tensors (the generator's) and principal-axis ones (the diagonal forms).
    if diagonal:
        for body in data["bodies"].values():
            if "inertia" in body:
                body["inertia"] = [float(np.trace(np.array(body["inertia"]))) / 3.0] * 3
    scene = parse_scene({"gravity": [0, 0, -9.81], **data}, "scene.yaml", ".")
    try:
        fast, slow, taken = both_paths(scene, steps=10, dt=1e-3)
    except SceneError:
        # A bar whose ends met: the array step says so too.
        with pytest.MonkeyPatch.context() as m:
            m.setattr(small_step, "fits", lambda world: False)
            with pytest.raises(SceneError):
                solve_scene(scene, steps=10, dt=1e-3)
        return
    assert taken, "a generated scene of at most 5 bodies takes the small step"
    scale = 1.0 + max(max(float(np.abs(b.velocity).max()), float(np.abs(b.angular_velocity).max()))
                      for b in slow.bodies)
    assert_same(fast, slow, 1e-11 * scale, 1e-8 * scale)


@pytest.mark.parametrize("name", ["pendulum", "chain", "four_bar", "hinged_door"])
def test_examples_take_the_small_step_and_match_the_array_step(name):
    from p3d_cli.constraints import load_scene
    import pathlib

    scene = load_scene(str(pathlib.Path(__file__).resolve().parents[2] / "examples" / f"{name}.yaml"))
    fast, slow, taken = both_paths(scene, steps=300, dt=1e-3)
    assert taken
    assert_same(fast, slow, 1e-12, 1e-10)


def test_the_trajectory_callback_sees_the_same_states(monkeypatch):
    scene = parse_scene({"gravity": [0, 0, -9.81], "bodies": {
        "wall": {"fixed": True},
        "arm": {"mass": 2.0, "inertia": [0.1, 0.2, 0.25], "position": [0.3, 0, 0], "angular_velocity": [0, 0, 1]},
        "tip": {"mass": 0.5, "inertia": [0.01, 0.01, 0.01], "position": [0.6, 0, 0], "velocity": [0, 0.5, 0]}},
        "constraints": [
            {"type": "hinge", "a": "wall", "b": "arm", "attach_a": [0, 0, 0], "axis_a": [0, 0, 1]},
            {"type": "ball", "a": "arm", "b": "tip", "attach_a": [0.3, 0, 0]}]}, "arm.yaml", ".")
    seen = {True: [], False: []}
    for small in (True, False):
        with monkeypatch.context() as m:
            if not small:
                m.setattr(small_step, "fits", lambda world: False)
            solve_scene(scene, steps=50, dt=2e-3, on_step=lambda t, bodies, s=small: seen[s].append((t, bodies)))
    assert len(seen[True]) == len(seen[False]) == 50
    for (t1, fast), (t2, slow) in zip(seen[True], seen[False]):
        assert t1 == t2
        for a, b in zip(fast, slow):
            np.testing.assert_allclose(a.center_of_mass, b.center_of_mass, rtol=0, atol=1e-13)
            np.testing.assert_allclose(a.velocity, b.velocity, rtol=0, atol=1e-10)


def range_errors_of_both_paths(monkeypatch, scene, steps: int) -> tuple[str, str]:
    """The RangeError messages of ``steps`` steps of dt = 1e200 on the small path, then on the
    general path (``small_step.fits`` forced false)."""
    messages = []
    for small in (True, False):
        with monkeypatch.context() as m:
            if not small:
                m.setattr(small_step, "fits", lambda world: False)
            with pytest.raises(RangeError) as info:
                solve_scene(scene, steps=steps, dt=1e200)
        messages.append(str(info.value))
    return messages[0], messages[1]


def test_an_overflowing_step_is_the_same_range_error_on_both_paths(monkeypatch):
    scene = parse_scene({"gravity": [0, 0, -9.81], "bodies": {
        "pivot": {"fixed": True},
        "bob": {"mass": 1.0, "inertia": [1e-3, 1e-3, 1e-3], "position": [1, 0, 0], "velocity": [0, 0, 1e150]}},
        "constraints": [{"type": "bar", "a": "pivot", "b": "bob", "attach_a": [0, 0, 0], "attach_b": [0, 0, 0],
                         "length": 1.0}]},
        "big.yaml", ".")
    small, general = range_errors_of_both_paths(monkeypatch, scene, steps=10)
    assert small == general
    assert "bob" in small and "step 1" in small


def test_an_overflowing_spin_is_a_range_error_not_a_math_error(monkeypatch):
    # ω dt = 1e300 × 1e10 overflows: math.sin(inf) raises ValueError, numpy gives nan.
    scene = parse_scene({"gravity": [0, 0, -9.81], "bodies": {
        "pivot": {"fixed": True},
        "bob": {"mass": 1.0, "inertia": [1.0, 1.0, 1.0], "position": [1, 0, 0], "angular_velocity": [1e150, 0, 0]}},
        "constraints": [{"type": "ball", "a": "pivot", "b": "bob", "attach_a": [0, 0, 0], "attach_b": [-1, 0, 0]}]},
        "spin.yaml", ".")
    small, general = range_errors_of_both_paths(monkeypatch, scene, steps=3)
    assert small == general
    assert "bob" in small and "overflows" in small


def test_a_large_scene_takes_the_array_step():
    links = 30
    bodies = {"anchor": {"fixed": True}}
    constraints = []
    for i in range(links):
        bodies[f"l{i}"] = {"mass": 1.0, "inertia": [1e-2, 1e-2, 1e-2], "position": [0, 0, -0.2 * i - 0.1]}
        constraints.append({"type": "ball", "a": "anchor" if i == 0 else f"l{i - 1}", "b": f"l{i}",
                            "attach_a": [0, 0, 0 if i == 0 else -0.1], "attach_b": [0, 0, 0.1]})
    scene = parse_scene({"gravity": [0, 0, -9.81], "bodies": bodies, "constraints": constraints}, "c.yaml", ".")
    from p3d_cli.constraints.bodies import resolve_inertials
    from p3d_cli.constraints.simulation import needed_bodies
    from p3d_cli.constraints.world import World

    world = World(scene, resolve_inertials(needed_bodies(scene, True, False)))
    assert world.rowset.m == 3 * links > small_step.SMALL_ROWS
    assert not small_step.fits(world)


# -- the float kernels against the numpy functions they restate ------------------------------------
@settings(max_examples=200, deadline=None)
@given(unit_quats(), st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3), st.sampled_from([1.0, 1e-3, 1e-9, 0.0]))
def test_turn_is_rotate_by_and_the_quaternion_matrix(q, v, size):
    theta = np.array(v) * size
    expect_q = rotate_by_many(np.array([q]), theta[None, :])[0]
    got_q, got_r = scalar.turn(tuple(q), *theta.tolist())
    np.testing.assert_allclose(got_q, expect_q, rtol=0, atol=4e-16)
    np.testing.assert_allclose(np.array(got_r).reshape(3, 3), quat_to_matrix(expect_q), rtol=0, atol=1e-15)


def test_turn_keeps_quarter_turns_exact():
    half = math.sqrt(0.5)
    _, r = scalar.turn((half, 0.0, 0.0, half), 0.0, 0.0, 0.0)
    assert r == [0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3), st.lists(st.floats(-1e-3, 1e-3), min_size=3, max_size=3),
       st.booleans())
def test_hinge_frames_agree(axis, tilt, flip):
    za = np.array(axis) + np.array([0.0, 0.0, 1e-3])
    za /= np.linalg.norm(za)
    zb = za + np.array(tilt)
    zb /= (-1 if flip else 1) * np.linalg.norm(zb)
    x, y, _, s = hinge_frames(za[None], zb[None])
    identity = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    hinge = make_joint("hinge", 0, 1, [0.0] * 3, [0.0] * 3, True, True, [0.0] * 6, [identity, identity], "",
                              (za.tolist(), zb.tolist()))
    errors = hinge.evaluate([0.0] * 6, [identity, identity])
    _, _, fx, fy = hinge._state
    np.testing.assert_allclose(fx, x[0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(fy, y[0], rtol=0, atol=1e-15)
    tilt = np.cross(za, s[0] * zb)
    np.testing.assert_allclose(errors, [0.0, 0.0, 0.0, tilt @ x[0], tilt @ y[0]], rtol=0, atol=1e-16)


@settings(max_examples=100, deadline=None)
@given(unit_quats(), unit_quats(), st.lists(st.floats(0.1, 2.0), min_size=3, max_size=3),
       st.lists(st.floats(-3, 3), min_size=3, max_size=3))
def test_inertia_products_agree_with_matrices_and_their_diagonal_forms(q1, q2, moments, w):
    r, t = quat_to_matrix(np.array(q1)), quat_to_matrix(np.array(q2))
    diag = np.diag(moments)
    inv = np.linalg.inv(diag)
    expect = t @ inv @ t.T @ (r @ diag @ r.T @ np.array(w))
    flat = lambda m: m.ravel().tolist()  # noqa: E731
    got = scalar.carry_spin(flat(r), flat(t), flat(diag), flat(inv), tuple(w))
    got_diag = scalar.carry_spin_diagonal(flat(r), flat(t), tuple(moments), tuple(np.diag(inv)), tuple(w))
    np.testing.assert_allclose(got, expect, rtol=1e-14, atol=1e-14)
    assert got_diag == got      # the general form only adds exact zeros
    world_inv = r @ inv @ r.T
    np.testing.assert_allclose(scalar.conjugate(flat(r), flat(inv)), world_inv.ravel(), rtol=1e-14, atol=1e-14)
    assert scalar.conjugate_diagonal(flat(r), tuple(np.diag(inv))) == scalar.conjugate(flat(r), flat(inv))


def test_the_rank_certificate_agrees_with_the_eigenvalue_rule():
    rng = np.random.default_rng(7)

    class Stub:
        redundant = False
        m = 6

    inverted = truncated = 0
    for trial in range(300):
        g = rng.normal(size=(6, 4 + trial % 5))          # rank min(6, columns): 4, 5 or 6
        g[:, 0] *= 10.0 ** rng.uniform(-7, 0)           # some nearly redundant
        system = g @ g.T
        stub = Stub()
        with np.errstate(all="ignore"):       # as solve_scene runs it: a singular inverse is nan
            pinv, rank = small_step._Island._pseudo_inverse(stub, system)
        values, vectors = np.linalg.eigh(system)
        keep = values > RANK_RTOL * system.diagonal().max()
        assert rank == int(keep.sum())
        expect = (vectors[:, keep] / values[keep]) @ vectors[:, keep].T
        # The same truncated inverse, summed in another order: rounding over the smallest kept
        # eigenvalue apart.
        np.testing.assert_allclose(pinv, expect, rtol=0, atol=1e-6 * np.abs(expect).max())
        # A redundant system is never certified full rank; a certified one was inverted.
        assert stub.redundant or rank == 6
        if not stub.redundant:
            np.testing.assert_array_equal(pinv, np.linalg.inv(system))
            inverted += 1
        else:
            truncated += 1
    assert inverted > 50 and truncated > 50
