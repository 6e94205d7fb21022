"""Many copies of one joint: the minimum-norm impulses, the rank, and linear cost in the copies.

The oracle is the dense minimum-norm solution built here from the ball joint's equations
(``J`` from ``v + ω × r``, ``W`` from the scene's masses), with numpy's pseudo-inverse.
"""

from __future__ import annotations

import numpy as np
import pytest

from p3d_cli.constraints import parse_scene, solve_scene, solver
from p3d_cli.constraints.rotation import quat_to_matrix

BODIES = {
    "a": {"mass": 2.0, "inertia": [[0.3, 0.05, 0], [0.05, 0.2, 0], [0, 0, 0.4]],
          "rotation": {"axis": [1, 2, 3], "degrees": 40}, "velocity": [1, 0, 0], "angular_velocity": [0, 0.5, 1]},
    "b": {"mass": 1.0, "inertia": [0.1, 0.2, 0.25], "position": [1, 0, 0],
          "rotation": {"axis": [0, 1, -1], "degrees": 75}, "velocity": [0, -1, 2]},
}
BALL = {"type": "ball", "a": "a", "b": "b", "attach_a": [0.5, 0, 0]}


def copies(n: int, dense_limit: int | None = None, **kw):
    """(scene, result) of ``n`` copies of ``BALL``; ``dense_limit`` replaces the solver's
    ``DENSE_LIMIT``."""
    scene = parse_scene({"bodies": BODIES, "constraints": [dict(BALL) for _ in range(n)]}, "dups", ".")
    with pytest.MonkeyPatch.context() as m:
        if dense_limit is not None:
            m.setattr(solver, "DENSE_LIMIT", dense_limit)
        return scene, solve_scene(scene, **kw)


def dense_minimum_norm(scene, n: int) -> np.ndarray:
    """λ = (J W Jᵀ)⁺ (-J u) for n copies of the ball joint, from first principles."""
    a, b = scene.bodies
    point = quat_to_matrix(a.rotation) @ BALL["attach_a"]            # world point, a at the origin
    rows, weights, u = [], [], []
    for body, sign in ((a, -1.0), (b, 1.0)):
        rot = quat_to_matrix(body.rotation)
        r = point - body.position                                    # centre of mass = body origin
        skew = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        rows.append(sign * np.hstack([np.eye(3), -skew]))
        w = np.zeros((6, 6))
        w[:3, :3] = np.eye(3) / body.mass
        w[3:, 3:] = rot @ np.linalg.inv(body.inertia) @ rot.T
        weights.append(w)
        u.append(np.concatenate([body.velocity, body.angular_velocity]))
    jac = np.tile(np.hstack(rows), (n, 1))
    weight = np.block([[weights[0], np.zeros((6, 6))], [np.zeros((6, 6)), weights[1]]])
    system = jac @ weight @ jac.T
    return np.linalg.pinv(system, rcond=1e-9, hermitian=True) @ (-jac @ np.concatenate(u))


@pytest.mark.parametrize("dense_limit", [240, 0])
def test_five_copies_match_the_dense_minimum_norm_solution(dense_limit):
    # dense_limit 0: 15 equations on 12 degrees of freedom take the body-space path.
    scene, result = copies(5, dense_limit=dense_limit)
    assert (result.equations, result.rank, result.redundant) == (15, 3, 12)
    expected = dense_minimum_norm(scene, 5).reshape(5, 3)
    scale = np.abs(expected).max()
    for c, lam in zip(result.constraints, expected):
        np.testing.assert_allclose(c.impulse, lam, rtol=0, atol=1e-12 * scale)
    # Minimum norm shares the load equally, and the motion is that of one joint.
    _, once = copies(1)
    for c in result.constraints:
        np.testing.assert_allclose(c.impulse, once.constraints[0].impulse / 5, rtol=0, atol=1e-12 * scale)
    for x, y in zip(once.bodies, result.bodies):
        np.testing.assert_allclose(y.velocity, x.velocity, rtol=0, atol=1e-12)
        np.testing.assert_allclose(y.angular_velocity, x.angular_velocity, rtol=0, atol=1e-12)


def test_two_thousand_copies_solve_and_share_the_impulse():
    n = 2000
    _, result = copies(n)
    _, once = copies(1)
    assert (result.equations, result.rank, result.redundant) == (3 * n, 3, 3 * n - 3)
    share = np.asarray(once.constraints[0].impulse) / n
    impulses = np.array([c.impulse for c in result.constraints])
    np.testing.assert_allclose(impulses, np.tile(share, (n, 1)), rtol=0, atol=1e-12 * np.abs(share).max())
    for x, y in zip(once.bodies, result.bodies):
        np.testing.assert_allclose(y.velocity, x.velocity, rtol=0, atol=1e-12)
    assert max(c.error for c in result.constraints) < 1e-12


def test_stepping_with_copies_moves_as_one_joint():
    gravity = {"gravity": [0, 0, -9.81]}
    one = parse_scene({**gravity, "bodies": BODIES, "constraints": [dict(BALL)]}, "one", ".")
    many = parse_scene({**gravity, "bodies": BODIES, "constraints": [dict(BALL) for _ in range(300)]}, "many", ".")
    first, second = solve_scene(one, steps=20, dt=1e-3), solve_scene(many, steps=20, dt=1e-3)
    assert (second.rank, second.equations) == (3, 900)
    for x, y in zip(first.bodies, second.bodies):
        np.testing.assert_allclose(y.position, x.position, rtol=0, atol=1e-12)
        np.testing.assert_allclose(y.velocity, x.velocity, rtol=0, atol=1e-10)
    assert second.max_position_error <= 1e-12
