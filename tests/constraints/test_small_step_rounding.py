"""The shortcuts of the small step that change numbers, but only by rounding.

``scalar.nudge`` turns a body by the position correction's small angles with truncated series
and without renormalising; ``small_islands._Factor.correction`` applies the correction's gain
``W Jᵀ K`` without the refinement step; ``body_kernels``' axial forms take a body of revolution's
inertia as ``d_a E + (d_j - d_a) z zᵀ``. Each is held here to an oracle computed otherwise: the
exact rotation in 50-digit decimal arithmetic, the exact solve in fractions, numpy's matrix
products.
"""

from __future__ import annotations

import decimal
import math
from fractions import Fraction

import numpy as np
import pytest
from helpers.joints import make_joint
from hypothesis import given, settings, strategies as st
from test_constraint_solver import unit_quats
from test_small_step import assert_same, both_paths

from p3d_cli.constraints import body_kernels, parse_scene, scalar, small_step
from p3d_cli.constraints.rotation import quat_to_matrix
from p3d_cli.constraints.small_islands import _Factor

scalar_axis = body_kernels.axis_of_revolution

D = decimal.Context(prec=50)


def exact_turn(q, rx, ry, rz):
    """``exp(θ/2) ⊗ q`` (θ = (rx, ry, rz)) and its rotation matrix, in 50-digit decimals from
    the power series of cos and sin (not from ``math``), rounded to floats at the end."""
    r = [D.create_decimal(float(v)) for v in (rx, ry, rz)]
    s = D.add(D.add(D.multiply(r[0], r[0]), D.multiply(r[1], r[1])), D.multiply(r[2], r[2]))
    h2 = D.divide(s, 4)                                   # (θ/2)²
    cos = sin_over = D.create_decimal(0)
    term_c, term_s = D.create_decimal(1), D.create_decimal("0.5")   # sin(h)/θ = (1/2) sin(h)/h
    for k in range(12):
        cos, sin_over = D.add(cos, term_c), D.add(sin_over, term_s)
        term_c = D.divide(D.multiply(-term_c, h2), (2 * k + 1) * (2 * k + 2))
        term_s = D.divide(D.multiply(-term_s, h2), (2 * k + 2) * (2 * k + 3))
    pw, px, py, pz = cos, *(D.multiply(sin_over, v) for v in r)
    qw, qx, qy, qz = (D.create_decimal(float(v)) for v in q)
    w = pw * qw - px * qx - py * qy - pz * qz
    x = pw * qx + px * qw + py * qz - pz * qy
    y = pw * qy - px * qz + py * qw + pz * qx
    z = pw * qz + px * qy - py * qx + pz * qw
    n = w * w + x * x + y * y + z * z
    matrix = [(w * w + x * x - y * y - z * z) / n, 2 * (x * y - w * z) / n, 2 * (x * z + w * y) / n,
              2 * (x * y + w * z) / n, (w * w - x * x + y * y - z * z) / n, 2 * (y * z - w * x) / n,
              2 * (x * z - w * y) / n, 2 * (y * z + w * x) / n, (w * w - x * x - y * y + z * z) / n]
    return [float(v) for v in (w, x, y, z)], [float(v) for v in matrix]


small_turns = st.tuples(*[st.floats(-1, 1)] * 3, st.sampled_from([0.0, 1e-16, 1e-12, 1e-9, 1e-7, 3e-6, 5.7e-5]))


@settings(max_examples=300, deadline=None)
@given(unit_quats(), small_turns)
def test_nudge_is_the_exact_turn_to_rounding(q, turn):
    d = [turn[0] * turn[3], turn[1] * turn[3], turn[2] * turn[3]]
    got_q, got_r = scalar.nudge(tuple(q), *d)
    expect_q, expect_r = exact_turn(q, -d[0], -d[1], -d[2])
    np.testing.assert_allclose(got_q, expect_q, rtol=0, atol=4e-16)
    np.testing.assert_allclose(got_r, expect_r, rtol=0, atol=6e-16)
    # And turn, which renormalises, to the same rounding.
    np.testing.assert_allclose(got_q, scalar.turn(tuple(q), -d[0], -d[1], -d[2])[0], rtol=0, atol=4e-16)


def test_nudge_takes_turn_for_large_or_non_finite_turns():
    q = (0.5, 0.5, -0.5, 0.5)
    for d in ((1e-4, 0.0, 0.0), (0.0, 0.3, -2.0), (math.inf, 0.0, 0.0)):
        got, expect = scalar.nudge(q, *d), scalar.turn(q, -d[0], -d[1], -d[2])
        assert str(got) == str(expect)              # str: nan == nan
    assert all(math.isnan(v) for v in scalar.nudge(q, math.nan, 0.0, 0.0)[0])
    # Just under the series' limit it is not turn's code, but the same numbers to rounding.
    d = (0.99e-4 / math.sqrt(3),) * 3
    np.testing.assert_allclose(scalar.nudge(q, *d)[0], exact_turn(q, *(-v for v in d))[0], rtol=0, atol=4e-16)


def test_nudges_keep_a_quaternion_unit_to_rounding():
    # Without renormalising: a step's few nudges (and many more) leave |q| at 1 to rounding.
    rng = np.random.default_rng(3)
    q = tuple(np.array([0.3, -0.1, 0.9, 0.2]) / np.linalg.norm([0.3, -0.1, 0.9, 0.2]))
    for _ in range(1000):
        q, r = scalar.nudge(q, *(rng.normal(size=3) * 1e-6).tolist())
    assert abs(math.fsum(v * v for v in q) - 1.0) < 1e-13
    m = np.array(r).reshape(3, 3)
    np.testing.assert_allclose(m @ m.T, np.eye(3), rtol=0, atol=1e-15)


def exact_solve(a, b):
    """The solution of ``a x = b`` in exact fractions (Gauss-Jordan), as floats."""
    n = len(b)
    m = [[Fraction(float(v)) for v in row] + [Fraction(float(bi))] for row, bi in zip(a, b)]
    for c in range(n):
        p = next(r for r in range(c, n) if m[r][c] != 0)
        m[c], m[p] = m[p], m[c]
        for r in range(n):
            if r != c and m[r][c] != 0:
                f = m[r][c] / m[c][c]
                m[r] = [x - f * y for x, y in zip(m[r], m[c])]
    return [m[r][n] / m[r][r] for r in range(n)]


def test_the_gain_correction_is_the_exact_correction_to_rounding():
    # Islands of 6 rows on 4 bodies with weights over two decades and rows scaled over two
    # more (condition numbers ~1e1-1e5). Without the refinement step the correction
    # W Jᵀ A⁻¹ e is off by at most a few cond(A) ε of itself; on a correction of the drift's
    # size (1e-6) that is under 1e-16, the rounding of a position of 1.
    rng = np.random.default_rng(11)
    conditions = []
    for _ in range(20):
        jac = rng.normal(size=(6, 24)) * (10.0 ** rng.uniform(-2, 0, size=6))[:, None]
        wjt = np.diag(10.0 ** rng.uniform(-1, 1, size=24)) @ jac.T
        system = jac @ wjt
        factor = _Factor(jac, wjt, system, np.linalg.inv(system), 6)
        errors = (rng.normal(size=6) * 1e-6).tolist()
        lam = exact_solve(system, errors)
        expect = np.array([float(sum(Fraction(float(w)) * x for w, x in zip(row, lam))) for row in wjt])
        got = factor.correction(errors)
        condition = float(np.linalg.cond(system))
        conditions.append(condition)
        assert np.abs(got - expect).max() <= 4 * condition * 2.2e-16 * np.abs(expect).max()
        assert np.abs(got - expect).max() < 1e-16
        # The velocity path's solve keeps its refinement: exact to rounding whatever cond(A).
        exact = np.array([float(x) for x in lam])
        np.testing.assert_allclose(factor.solve(np.array(errors)), exact, rtol=0, atol=1e-15 * np.abs(exact).max())
    assert max(conditions) > 1e3          # the refinement would have had something to recover


def flat(m):
    return [float(v) for v in np.asarray(m).ravel()]


@settings(max_examples=200, deadline=None)
@given(unit_quats(), unit_quats(), st.sampled_from([0, 1, 2]), st.floats(1e-4, 1e2), st.floats(1e-4, 1e2),
       st.lists(st.floats(-10.0, 10.0), min_size=3, max_size=3))
def test_bodies_of_revolution_take_the_axial_forms_to_rounding(q1, q2, axis, across, along, w):
    moments = [across] * 3
    moments[axis] = along
    inverse = [1.0 / m for m in moments]
    axial = scalar_axis(moments, inverse)
    assert axial == (axis if across != along else 2, across, along, 1.0 / across, 1.0 / along)
    r, t = quat_to_matrix(np.array(q1)), quat_to_matrix(np.array(q2))
    # Oracle: the matrix products in numpy, R I Rᵀ ω carried to T I⁻¹ Tᵀ.
    momentum = r @ np.diag(moments) @ r.T @ np.array(w)
    expect = t @ np.diag(inverse) @ t.T @ momentum
    got = body_kernels.carry_spin_axial(r[:, axial[0]].tolist(), t[:, axial[0]].tolist(), axial, tuple(w))
    np.testing.assert_allclose(got, expect, rtol=0, atol=1e-15 * max(moments) * max(inverse) * (1 + np.abs(w).max()))
    world_inv = r @ np.diag(inverse) @ r.T
    got_inv = body_kernels.conjugate_axial(r[:, axial[0]].tolist(), axial)
    np.testing.assert_allclose(got_inv, world_inv.ravel(), rtol=0, atol=1e-15 * max(inverse))
    assert got_inv[1] == got_inv[3] and got_inv[2] == got_inv[6] and got_inv[5] == got_inv[7]


def test_only_two_equal_moments_make_a_body_of_revolution():
    assert scalar_axis((1.0, 2.0, 3.0), (1.0, 0.5, 1 / 3)) is None
    assert scalar_axis((2.0, 1.0, 2.0), (0.5, 1.0, 0.5))[0] == 1
    assert scalar_axis((1.0, 2.0, 2.0), (1.0, 0.5, 0.5))[0] == 0
    # Equal moments whose inverses differ (cannot happen for 1/x, but the test is on both).
    assert scalar_axis((1.0, 1.0, 3.0), (1.0, 0.9, 1 / 3)) is None


# -- bodies read along one axis only (small_step._axis_columns) -----------------------------------
ROD_TURN = {0: {"axis": [0, 1, 0], "degrees": -90}, 1: {"axis": [1, 0, 0], "degrees": 90},
            2: {"axis": [0, 0, 1], "degrees": 0}}


@st.composite
def rod_chains(draw):
    """A chain of rods (bodies of revolution about body axis ``j``) hanging from an anchor,
    joined on their axes by balls, bars or hinges (about the rods' axis, or across it),
    with random velocities; ``off_axis`` moves one joint off the axis (no body is then read
    along one column only, on that joint's bodies)."""
    j = draw(st.integers(0, 2))
    n = draw(st.integers(1, 4))
    half = draw(st.floats(0.05, 0.5))
    unit = [0.0, 0.0, 0.0]
    unit[j] = half
    bodies: dict = {"anchor": {"fixed": True}}
    constraints = []
    for i in range(1, n + 1):
        across = draw(st.floats(0.1, 2.0))
        along = across * draw(st.floats(0.05, 1.9))       # a solid's: along <= 2 across
        moments = [across] * 3
        moments[j] = along
        bodies[f"rod{i}"] = {"mass": draw(st.floats(0.2, 3.0)), "inertia": moments,
                             "position": [0.0, 0.0, -half * (2 * i - 1)], "rotation": ROD_TURN[j],
                             "velocity": draw(st.lists(st.floats(-2, 2), min_size=3, max_size=3)),
                             "angular_velocity": draw(st.lists(st.floats(-5, 5), min_size=3, max_size=3))}
        a = "anchor" if i == 1 else f"rod{i - 1}"
        entry = {"type": draw(st.sampled_from(["ball", "hinge", "bar"])), "a": a, "b": f"rod{i}",
                 "attach_a": [0.0, 0.0, 0.0] if i == 1 else [-x for x in unit], "attach_b": list(unit)}
        if entry["type"] == "bar":        # from a point half a rod's half-length beyond its end
            entry["attach_b"] = [1.5 * x for x in unit]
        if entry["type"] == "hinge":
            entry["axis_a"] = [0.0, 0.0, 1.0] if i == 1 else list(draw(st.sampled_from([unit, [half, half, 0.0]])))
            entry.pop("attach_b")         # the same world point
        constraints.append(entry)
    off_axis = draw(st.booleans())
    if off_axis:
        constraints[-1]["attach_a"] = [0.01, 0.02, 0.0] if n == 1 else [0.01 - x for x in unit]
    on_axis = not off_axis and all(c.get("axis_a", unit) in (unit, [0.0, 0.0, 1.0]) for c in constraints)
    return {"gravity": [0, 0, -9.81], "bodies": bodies, "constraints": constraints}, j, on_axis


@settings(max_examples=40, deadline=None)
@given(rod_chains())
def test_rods_read_along_their_axis_step_as_the_array_path(chain):
    data, j, on_axis = chain
    seen = []
    real = small_step._axis_columns

    def spy(*args):
        seen.append(real(*args))
        return seen[-1]

    scene = parse_scene(data, "scene.yaml", ".")
    with pytest.MonkeyPatch.context() as m:
        m.setattr(small_step, "_axis_columns", spy)
        fast, slow, taken = both_paths(scene, steps=20, dt=1e-3)
    assert taken and seen
    # Every rod whose joints are all on its axis (and whose hinges turn about it, or across it:
    # then not) is kept as that one column.
    columns = seen[0]
    assert columns[0] is None                     # the anchor
    assert all(c in (None, j) for c in columns)
    if on_axis:
        assert columns[1:] == [j] * (len(columns) - 1)
    scale = 1.0 + max(max(float(np.abs(b.velocity).max()), float(np.abs(b.angular_velocity).max()))
                      for b in slow.bodies)
    assert_same(fast, slow, 1e-11 * scale, 1e-8 * scale)


def test_a_chain_of_rods_is_read_along_one_column():
    rot = [[1.0, 0, 0, 0, 1.0, 0, 0, 0, 1.0]] * 3
    com = [0.0] * 9
    axial = [None, (2, 1.0, 0.1, 1.0, 10.0), (2, 1.0, 0.1, 1.0, 10.0)]
    on_axis = [make_joint("ball", 0, 1, [0.0] * 3, [0, 0, 0.1], False, True, com, rot, ""),
               make_joint("hinge", 1, 2, [0, 0, -0.1], [0, 0, 0.1], True, True, com, rot, "",
                          ([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]))]
    assert small_step._axis_columns(3, axial, on_axis) == [None, 2, 2]
    across = on_axis[:1] + [make_joint("hinge", 1, 2, [0, 0, -0.1], [0, 0, 0.1], True, True, com, rot, "",
                                       ([1.0, 0.0, 0.0], [1.0, 0.0, 0.0]))]
    assert small_step._axis_columns(3, axial, across) == [None, None, None]
    off = on_axis[:1] + [make_joint("ball", 1, 2, [0.1, 0, -0.1], [0, 0, 0.1], True, True, com, rot, "")]
    assert small_step._axis_columns(3, axial, off) == [None, None, 2]
    assert small_step._axis_columns(3, [None, None, axial[2]], on_axis) == [None, None, 2]
