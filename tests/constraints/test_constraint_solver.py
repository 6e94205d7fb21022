"""Invariants of one velocity solve on generated scenes of rotated bodies with offset centres.

Checks are written independently of the library's own bookkeeping: point velocities
``v + ω × r`` from the reported velocities, momenta from the scene's masses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, strategies as st

from p3d_cli.constraints import parse_scene, solve_scene, solver
from p3d_cli.constraints.rotation import quat_to_matrix

finite = st.floats(-1.0, 1.0, allow_nan=False)
vec3 = st.lists(finite, min_size=3, max_size=3)


@st.composite
def unit_quats(draw):
    q = np.array(draw(st.lists(st.floats(-1, 1), min_size=4, max_size=4)))
    if np.linalg.norm(q) < 0.1:
        q = np.array([1.0, 0, 0, 0])
    return (q / np.linalg.norm(q)).tolist()


@st.composite
def inertias(draw):
    # Principal moments from a solid's second moments (always obey the triangle inequality),
    # turned by a random rotation: a full, non-diagonal tensor.
    s = np.array(draw(st.lists(st.floats(0.05, 2.0), min_size=3, max_size=3)))
    principal = np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
    r = quat_to_matrix(np.array(draw(unit_quats())))
    return (r @ np.diag(principal) @ r.T).tolist()


@st.composite
def scenes(draw, allow_fixed=True, min_bodies=2, max_bodies=5):
    n = draw(st.integers(min_bodies, max_bodies))
    fixed_count = draw(st.integers(0, 1)) if allow_fixed else 0
    bodies = {}
    for i in range(n):
        name = f"b{i}"
        if i < fixed_count:
            bodies[name] = {"fixed": True, "position": draw(vec3), "rotation": {"quat": draw(unit_quats())}}
            continue
        bodies[name] = {
            "mass": draw(st.floats(0.2, 5.0)),
            "inertia": draw(inertias()),
            "center_of_mass": [0.5 * x for x in draw(vec3)],
            "position": [2 * x for x in draw(vec3)],
            "rotation": {"quat": draw(unit_quats())},
            "velocity": [3 * x for x in draw(vec3)],
            "angular_velocity": [3 * x for x in draw(vec3)],
        }
    names = list(bodies)
    constraints = []
    for _ in range(draw(st.integers(1, 2 * n))):
        a, b = draw(st.lists(st.sampled_from(names), min_size=2, max_size=2, unique=True))
        if bodies[a].get("fixed") and bodies[b].get("fixed"):
            continue
        kind = draw(st.sampled_from(["ball", "hinge", "bar"]))
        entry = {"type": kind, "a": a, "b": b, "attach_a": draw(vec3)}
        if kind == "bar":
            entry["attach_b"] = [x + 0.3 for x in draw(vec3)]
        if kind == "hinge":
            entry["axis_a"] = [x + 0.5 for x in draw(vec3)]   # axis_b: the same world axis
        constraints.append(entry)
    if not constraints:
        constraints.append({"type": "ball", "a": names[-1], "b": names[-2], "attach_a": [0, 0, 0]})
    return {"bodies": bodies, "constraints": constraints}


def solve_data(data, dense_limit: int | None = None, **kw):
    """(scene, result) of ``data``; ``dense_limit`` replaces the solver's ``DENSE_LIMIT`` (0: no
    island is solved dense)."""
    scene = parse_scene(data, "scene.yaml", ".")
    with pytest.MonkeyPatch.context() as m:
        if dense_limit is not None:
            m.setattr(solver, "DENSE_LIMIT", dense_limit)
        return scene, solve_scene(scene, **kw)


def world_points(scene, result):
    """Per body: (rotation, centre of mass) after the solve, from the scene's values."""
    states = {b.name: b for b in result.bodies}
    out = {}
    for body in scene.bodies:
        rot = quat_to_matrix(states[body.name].rotation)
        com_body = body.center_of_mass if body.center_of_mass is not None else np.zeros(3)
        out[body.name] = (rot, states[body.name].position + rot @ com_body)
    return out


def constraint_residuals(scene, result) -> list[float]:
    """Velocity equations of every constraint, recomputed from the reported motion."""
    states = {b.name: b for b in result.bodies}
    poses = world_points(scene, result)
    out = []
    for c in scene.constraints:
        (ra, ca), (rb, cb) = poses[c.a], poses[c.b]
        pa, pb = states[c.a].position + ra @ c.attach_a, states[c.b].position + rb @ c.attach_b
        va = states[c.a].velocity + np.cross(states[c.a].angular_velocity, pa - ca)
        vb = states[c.b].velocity + np.cross(states[c.b].angular_velocity, pb - cb)
        if c.type == "ball":
            out.append(float(np.abs(vb - va).max()))
        elif c.type == "bar":
            d = (pb - pa) / np.linalg.norm(pb - pa)
            out.append(abs(float((vb - va) @ d)))
        else:
            z = ra @ c.values["axis_a"]
            rel = np.cross(states[c.b].angular_velocity - states[c.a].angular_velocity, z)
            out.append(max(float(np.abs(vb - va).max()), float(np.abs(rel).max())))
    return out


def momenta(scene, result, which: str):
    """Linear and angular momentum (about the origin) of the free bodies, from scene masses."""
    states = {b.name: b for b in result.bodies}
    poses = world_points(scene, result)
    linear, angular = np.zeros(3), np.zeros(3)
    for body in scene.bodies:
        if body.fixed:
            continue
        rot, com = poses[body.name]
        v = body.velocity if which == "before" else states[body.name].velocity
        w = body.angular_velocity if which == "before" else states[body.name].angular_velocity
        linear += body.mass * v
        angular += body.mass * np.cross(com, v) + rot @ body.inertia @ rot.T @ w
    return linear, angular


def scale_of(data) -> float:
    return 1.0 + max(max(abs(x) for x in b.get("velocity", [0]) + b.get("angular_velocity", [0]))
                     for b in data["bodies"].values())


@given(scenes())
def test_every_constraint_equation_holds_after_a_solve(data):
    scene, result = solve_data(data)
    tol = 1e-9 * scale_of(data)
    assert max(constraint_residuals(scene, result)) < tol
    assert max(c.error for c in result.constraints) < tol
    for body in result.bodies:
        assert np.isfinite(body.velocity).all() and np.isfinite(body.angular_velocity).all()


@given(scenes(allow_fixed=False))
def test_momentum_of_a_free_island_is_unchanged(data):
    scene, result = solve_data(data)
    lin0, ang0 = momenta(scene, result, "before")
    lin1, ang1 = momenta(scene, result, "after")
    tol = 1e-9 * scale_of(data) * 50
    np.testing.assert_allclose(lin1, lin0, atol=tol)
    np.testing.assert_allclose(ang1, ang0, atol=tol)
    np.testing.assert_allclose(result.momentum[1], result.momentum[0], atol=tol)
    np.testing.assert_allclose(result.angular_momentum[1], result.angular_momentum[0], atol=tol)


@given(scenes())
def test_kinetic_energy_never_rises(data):
    _, result = solve_data(data)
    before, after = result.kinetic_energy
    assert after <= before * (1 + 1e-12) + 1e-15
    assert after >= 0


@given(scenes(), st.randoms(use_true_random=False))
def test_result_does_not_depend_on_listing_order(data, rnd):
    _, first = solve_data(data)
    names = list(data["bodies"])
    rnd.shuffle(names)
    order = list(range(len(data["constraints"])))
    rnd.shuffle(order)
    shuffled = {"bodies": {n: data["bodies"][n] for n in names},
                "constraints": [data["constraints"][k] for k in order]}
    _, second = solve_data(shuffled)
    tol = 1e-9 * scale_of(data)
    one, two = {b.name: b for b in first.bodies}, {b.name: b for b in second.bodies}
    for name in names:
        np.testing.assert_allclose(two[name].velocity, one[name].velocity, atol=tol)
        np.testing.assert_allclose(two[name].angular_velocity, one[name].angular_velocity, atol=tol)
    assert first.rank == second.rank and first.equations == second.equations
    for new_index, old_index in enumerate(order):
        np.testing.assert_allclose(np.atleast_1d(second.constraints[new_index].impulse),
                                   np.atleast_1d(first.constraints[old_index].impulse), atol=1e-7 * scale_of(data))


@given(scenes())
def test_sparse_path_agrees_with_dense_path(data):
    _, dense = solve_data(data)
    _, sparse = solve_data(data, dense_limit=0)
    assert sparse.rank == dense.rank
    tol = 1e-8 * scale_of(data)
    for d, s in zip(dense.bodies, sparse.bodies):
        np.testing.assert_allclose(s.velocity, d.velocity, atol=tol)
        np.testing.assert_allclose(s.angular_velocity, d.angular_velocity, atol=tol)
    for d, s in zip(dense.constraints, sparse.constraints):
        np.testing.assert_allclose(np.atleast_1d(s.impulse), np.atleast_1d(d.impulse), atol=1e-6 * scale_of(data))


def two_bodies(**extra):
    return {
        "a": {"mass": 2.0, "inertia": [[0.3, 0.05, 0], [0.05, 0.2, 0], [0, 0, 0.4]],
              "center_of_mass": [0.1, -0.2, 0.05], "rotation": {"axis": [1, 2, 3], "degrees": 40},
              "velocity": [1, 0, 0], "angular_velocity": [0, 0.5, 1]},
        "b": {"mass": 1.0, "inertia": [0.1, 0.2, 0.25], "position": [1, 0, 0],
              "rotation": {"axis": [0, 1, -1], "degrees": 75}, "velocity": [0, -1, 2], **extra},
    }


@pytest.mark.parametrize("dense_limit", [240, 0])
def test_the_same_constraint_twice_is_redundant_not_nan(dense_limit):
    ball = {"type": "ball", "a": "a", "b": "b", "attach_a": [0.5, 0, 0]}
    _, once = solve_data({"bodies": two_bodies(), "constraints": [ball]}, dense_limit=dense_limit)
    scene, twice = solve_data({"bodies": two_bodies(), "constraints": [ball, dict(ball)]}, dense_limit=dense_limit)
    assert (twice.rank, twice.equations, twice.redundant) == (3, 6, 3)
    assert (once.rank, once.redundant) == (3, 0)
    # Minimum norm splits the impulse evenly between the two copies; the motion is the same.
    np.testing.assert_allclose(twice.constraints[0].impulse, 0.5 * once.constraints[0].impulse, atol=1e-12)
    np.testing.assert_allclose(twice.constraints[1].impulse, 0.5 * once.constraints[0].impulse, atol=1e-12)
    for x, y in zip(once.bodies, twice.bodies):
        np.testing.assert_allclose(y.velocity, x.velocity, atol=1e-12)
    assert max(constraint_residuals(scene, twice)) < 1e-12


@pytest.mark.parametrize("dense_limit", [240, 0])
def test_closed_loop_of_hinges_reports_its_redundancy(dense_limit):
    # Three bodies in a triangle joined by three parallel hinges: 15 equations, and the planar
    # loop leaves 3 of them redundant (out-of-plane directions are fixed twice over).
    bodies = {f"p{i}": {"mass": 1.0 + i, "inertia": [0.1, 0.2, 0.15],
                        "position": [math.cos(2 * math.pi * i / 3), math.sin(2 * math.pi * i / 3), 0],
                        "rotation": {"axis": [0, 0, 1], "degrees": 20 * i},
                        "velocity": [0.1 * i, -0.2, 0.3], "angular_velocity": [0.2, 0, i]} for i in range(3)}
    corners = [np.array([math.cos(a), math.sin(a), 0]) * 0.5 for a in (math.pi / 3, math.pi, 5 * math.pi / 3)]
    constraints = []
    for i, corner in enumerate(corners):
        a, b = f"p{i}", f"p{(i + 1) % 3}"
        rot = quat_to_matrix(np.array([math.cos(math.radians(10 * i)), 0, 0, math.sin(math.radians(10 * i))]))
        constraints.append({"type": "hinge", "a": a, "b": b,
                            "attach_a": (rot.T @ (corner * 2 - np.array(bodies[a]["position"]))).tolist(),
                            "axis_a": [0, 0, 1]})
    scene, result = solve_data({"bodies": bodies, "constraints": constraints}, dense_limit=dense_limit)
    assert result.equations == 15 and result.rank == 12 and result.redundant == 3
    assert max(constraint_residuals(scene, result)) < 1e-12
    assert all(np.isfinite(np.atleast_1d(c.impulse)).all() for c in result.constraints)


def test_fixed_body_takes_part_with_zero_inverse_mass():
    bodies = {"ground": {"fixed": True, "rotation": {"axis": [1, 1, 0], "degrees": 33}, "position": [0, 0, 1]},
              "bob": {"mass": 3.0, "inertia": [0.1, 0.1, 0.1], "position": [0, 0, 0],
                      "velocity": [1.0, 2.0, 3.0]}}
    cons = [{"type": "ball", "a": "ground", "b": "bob", "attach_b": [0, 0, 0]}]
    scene, result = solve_data({"bodies": bodies, "constraints": cons})
    states = {b.name: b for b in result.bodies}
    # The bob's attachment point is its centre, held by an immovable body: it stops dead.
    np.testing.assert_allclose(states["bob"].velocity, 0, atol=1e-15)
    np.testing.assert_allclose(states["ground"].velocity, 0)
    np.testing.assert_allclose(result.constraints[0].impulse, [-3.0, -6.0, -9.0], atol=1e-12)


def test_bodies_that_nothing_links_are_unchanged():
    bodies = two_bodies()
    bodies["loner"] = {"mass": 1.0, "inertia": [1, 1, 1], "velocity": [5, 6, 7], "angular_velocity": [1, 2, 3],
                       "rotation": {"axis": [0, 0, 1], "degrees": 10}}
    cons = [{"type": "bar", "a": "a", "b": "b", "attach_a": [0, 0, 0], "attach_b": [0.2, 0, 0]}]
    _, result = solve_data({"bodies": bodies, "constraints": cons})
    loner = result.bodies[2]
    assert loner.name == "loner" and not loner.constrained
    np.testing.assert_array_equal(loner.velocity, [5, 6, 7])
    np.testing.assert_array_equal(loner.angular_velocity, [1, 2, 3])
    assert result.islands == 1


def test_independent_pendulums_are_separate_islands():
    bodies = {"ground": {"fixed": True}}
    cons = []
    for i in range(4):
        bodies[f"bob{i}"] = {"mass": 1.0 + i, "inertia": [0.01] * 3, "position": [i, 0, -1], "velocity": [1, 0, -1]}
        cons.append({"type": "bar", "a": "ground", "b": f"bob{i}", "attach_a": [i, 0, 0], "attach_b": [0, 0, 0]})
    _, result = solve_data({"bodies": bodies, "constraints": cons})
    assert result.islands == 4 and result.rank == 4
    for body in result.bodies[1:]:
        np.testing.assert_allclose(body.velocity, [1, 0, 0], atol=1e-15)


def test_rotated_body_uses_world_frame_inverse_inertia():
    # A free body hit by a ball joint to a fixed point away from its centre: the resulting
    # spin must be I_world⁻¹ (r × p), with I_world = R I Rᵀ; the same body unrotated gives a
    # different answer, so a body-frame inverse inertia would fail this.
    inertia = np.diag([0.3, 0.5, 0.7])
    bodies = {"ground": {"fixed": True},
              "body": {"mass": 1.0, "inertia": inertia.tolist(), "rotation": {"axis": [1, 1, 1], "degrees": 50},
                       "velocity": [0, 0, 1]}}
    cons = [{"type": "ball", "a": "ground", "b": "body", "attach_a": [0.3, 0.2, 0.0]}]
    scene, result = solve_data({"bodies": bodies, "constraints": cons})
    body = result.bodies[1]
    rot = quat_to_matrix(body.rotation)
    p = np.asarray(result.constraints[0].impulse)
    r = np.array([0.3, 0.2, 0.0])
    np.testing.assert_allclose(body.angular_velocity, rot @ np.linalg.inv(inertia) @ rot.T @ np.cross(r, p),
                               atol=1e-12)
    np.testing.assert_allclose(body.velocity, np.array([0, 0, 1]) + p, atol=1e-12)
    np.testing.assert_allclose(body.velocity + np.cross(body.angular_velocity, r), 0, atol=1e-12)


def test_a_large_island_without_scipy_names_the_extra(monkeypatch):
    """Issue 24.5: scipy is the extra 'solve'; without it a large island is one clear error."""
    import sys

    from p3d_cli.errors import MissingExtraError

    for name in [m for m in sys.modules if m == "scipy" or m.startswith("scipy.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "scipy", None)   # import scipy now raises ImportError
    ball = {"type": "ball", "a": "a", "b": "b", "attach_a": [0.5, 0, 0]}
    _, small = solve_data({"bodies": two_bodies(), "constraints": [ball]})   # small islands need no scipy
    assert small.rank == 3
    with pytest.raises(MissingExtraError) as missing:
        solve_data({"bodies": two_bodies(), "constraints": [ball]}, dense_limit=0)
    assert missing.value.where == "solve" and "'scipy>=1.10'" in missing.value.hint
