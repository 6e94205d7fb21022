"""The shortcuts of ``scalar`` are exact: the same numbers as the general formulas they skip.

``turn`` leaves out ``cos(θ/2)`` below 1e-8 rad (it rounds to 1.0) and the division by an ``n``
of exactly 1; ``Joint.points`` and ``Hinge`` take a column of ``R`` for an offset or axis along
one body axis (the products with its zero components are exact zeros). Each is checked here
bit for bit (``==``, which only ignores the sign of a zero) against the general formula,
written out as it was before the shortcut.
"""

from __future__ import annotations

import math

from helpers.joints import make_joint
from hypothesis import given, settings, strategies as st
from test_constraint_solver import unit_quats

from p3d_cli.constraints import scalar


def general_turn(q, rx, ry, rz):
    """``scalar.turn`` without its shortcuts (the formula of the code before them)."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    half = 0.5 * angle
    factor = math.sin(half) / angle if angle >= 1e-8 else 0.5 - angle * angle / 48.0
    pw, px, py, pz = math.cos(half), factor * rx, factor * ry, factor * rz
    qw, qx, qy, qz = q
    w = pw * qw - px * qx - py * qy - pz * qz
    x = pw * qx + px * qw + py * qz - pz * qy
    y = pw * qy - px * qz + py * qw + pz * qx
    z = pw * qz + px * qy - py * qx + pz * qw
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    n = ww + xx + yy + zz
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    return (w, x, y, z), [(ww + xx - yy - zz) / n, (2 * xy - 2 * wz) / n, (2 * xz + 2 * wy) / n,
                          (2 * xy + 2 * wz) / n, (ww - xx + yy - zz) / n, (2 * yz - 2 * wx) / n,
                          (2 * xz - 2 * wy) / n, (2 * yz + 2 * wx) / n, (ww - xx - yy + zz) / n]


turn_vectors = st.tuples(*[st.floats(-1, 1)] * 3, st.sampled_from([1e-20, 1e-14, 1e-10, 9.9e-9, 1e-8, 1e-4, 1.0]))


@settings(max_examples=300, deadline=None)
@given(unit_quats(), turn_vectors)
def test_turn_is_the_general_formula_bit_for_bit(q, v):
    rx, ry, rz, scale = v
    rx, ry, rz = rx * scale, ry * scale, rz * scale
    assert scalar.turn(tuple(q), rx, ry, rz) == general_turn(tuple(q), rx, ry, rz)


def test_turn_takes_both_of_its_branches_and_the_cosine_it_skips_is_one():
    # The skipped cos(θ/2) is 1.0 for every θ below 1e-8 (it would be 1 - 1.25e-17 at most).
    assert all(math.cos(0.5 * t) == 1.0 for t in (1e-8 * (1 - 1e-16), 5e-9, 1e-12, 0.0))
    assert math.cos(0.5 * 1e-7) < 1.0          # a shortcut that is not vacuous
    q = (0.5, 0.5, 0.5, 0.5)
    for r in ((1e-9, 0.0, 0.0), (0.0, 0.0, 0.0), (1e-3, -2e-3, 0.5)):
        assert scalar.turn(q, *r) == general_turn(q, *r)


def rotation(q):
    return scalar.turn(tuple(q), 0.0, 0.0, 0.0)[1]


axial_offsets = st.tuples(st.integers(0, 2), st.floats(-10, 10).filter(lambda o: o != 0.0))


@settings(max_examples=200, deadline=None)
@given(unit_quats(), unit_quats(), axial_offsets, axial_offsets,
       st.lists(st.floats(-5, 5), min_size=6, max_size=6))
def test_axial_offsets_and_axes_give_the_general_numbers(qa, qb, off_a, off_b, com):
    rot = [rotation(qa), rotation(qb)]
    oa = [0.0, 0.0, 0.0]
    oa[off_a[0]] = off_a[1]
    ob = [0.0, 0.0, 0.0]
    ob[off_b[0]] = off_b[1]
    axis_a, axis_b = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    axis_a[off_b[0]], axis_b[off_a[0]] = 1.0, -1.0
    for kind in ("ball", "hinge", "bar"):
        fast = make_joint(kind, 0, 1, oa, ob, True, True, com, rot, "here", (axis_a, axis_b), 0.3)
        slow = make_joint(kind, 0, 1, oa, ob, True, True, com, rot, "here", (axis_a, axis_b), 0.3)
        assert fast.axial_a == (off_a[0], off_a[1]) and fast.axial_b == (off_b[0], off_b[1])
        slow.axial_a = slow.axial_b = None
        if kind == "hinge":
            assert fast.along_a is not None and fast.along_b is not None
            slow.along_a = slow.along_b = None
        assert fast.evaluate(com, rot) == slow.evaluate(com, rot)
        if kind != "bar" or slow._state[3] != 0.0:
            assert fast.entries() == slow.entries()


def test_an_offset_off_the_axes_or_not_finite_takes_the_general_form():
    assert scalar.axial([0.0, 0.1, 0.0]) == (1, 0.1)
    assert scalar.axial([0.1, 0.1, 0.0]) is None
    assert scalar.axial([0.0, 0.0, 0.0]) is None
    assert scalar.axial([0.0, math.inf, 0.0]) is None


@settings(max_examples=200, deadline=None)
@given(unit_quats(), unit_quats(), axial_offsets, axial_offsets,
       st.lists(st.floats(-5, 5), min_size=6, max_size=6))
def test_the_both_sides_axial_path_gives_the_general_numbers(qa, qb, off_a, off_b, com):
    # Joint.points' first branch (both sides free and axial, one attribute of indices) against
    # the general products, for every joint type, bit for bit; and a fixed side never takes it.
    rot = [rotation(qa), rotation(qb)]
    oa, ob = [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    oa[off_a[0]], ob[off_b[0]] = off_a[1], off_b[1]
    axes = ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0])
    for kind in ("ball", "hinge", "bar"):
        fast = make_joint(kind, 0, 1, oa, ob, True, True, com, rot, "here", axes, 0.3)
        slow = make_joint(kind, 0, 1, oa, ob, True, True, com, rot, "here", axes, 0.3)
        assert fast._both_axial is not None
        slow._both_axial = slow.axial_a = slow.axial_b = None
        assert fast.evaluate(com, rot) == slow.evaluate(com, rot)
        if kind != "bar" or slow._state[3] != 0.0:
            assert fast.entries() == slow.entries()
        fixed = make_joint(kind, 0, 1, oa, ob, False, True, com, rot, "here", axes, 0.3)
        assert fixed._both_axial is None


@settings(max_examples=300, deadline=None)
@given(unit_quats(), turn_vectors, st.integers(0, 2))
def test_a_turned_column_is_that_column_of_the_matrix_bit_for_bit(q, v, j):
    # turn and nudge with column=j: the same quaternion and the j-th column of the full matrix.
    rx, ry, rz = v[0] * v[3], v[1] * v[3], v[2] * v[3]
    for kernel in (scalar.turn, scalar.nudge):
        full_q, full_r = kernel(tuple(q), rx, ry, rz)
        got_q, got_c = kernel(tuple(q), rx, ry, rz, j)
        assert got_q == full_q and got_c == full_r[j::3]
    nan_q, nan_c = scalar.turn(tuple(q), math.inf, 0.0, 0.0, j)
    assert len(nan_c) == 3 and all(math.isnan(c) for c in nan_c)
