"""Rotations: axis-angle, quaternions, composition order, parsing and refusals."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.errors import UsageError
from p3d_cli.geometry.rotation import (
    compose_rotations,
    cos_sin_degrees,
    parse_quaternion,
    parse_turn,
    rotation_from_axis_degrees,
    rotation_from_quaternion,
)

EX, EY, EZ = np.eye(3)


def test_right_hand_rule():
    np.testing.assert_array_equal(rotation_from_axis_degrees("z", 90) @ EX, EY)
    np.testing.assert_array_equal(rotation_from_axis_degrees("x", 90) @ EY, EZ)
    np.testing.assert_array_equal(rotation_from_axis_degrees("y", 90) @ EZ, EX)


@pytest.mark.parametrize("deg", [0, 90, 180, 270, -90, 360, 450, -720])
def test_quarter_turns_are_exact(deg):
    r = rotation_from_axis_degrees("z", deg)
    assert set(np.unique(r)) <= {-1.0, 0.0, 1.0}


def test_cos_sin_degrees_accurate():
    for deg in np.linspace(-1000, 1000, 301):
        c, s = cos_sin_degrees(deg)
        assert math.isclose(c, math.cos(math.radians(deg)), abs_tol=1e-13)
        assert math.isclose(s, math.sin(math.radians(deg)), abs_tol=1e-13)


def test_composition_applies_each_turn_after_the_previous_about_world_axes():
    rz, rx = rotation_from_axis_degrees("z", 90), rotation_from_axis_degrees("x", 90)
    r = compose_rotations([rz, rx])
    np.testing.assert_array_equal(r, rx @ rz)
    np.testing.assert_array_equal(r @ EX, EZ)      # x -> y (by z), then y -> z (by x)


def test_vector_axis():
    r = rotation_from_axis_degrees([1, 1, 0], 180)
    np.testing.assert_allclose(r @ EX, EY, atol=1e-15)
    np.testing.assert_allclose(parse_turn("1,1,0:180"), r, atol=0)


def test_quaternion_matches_axis_angle_and_sign():
    axis = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    theta = math.radians(70)
    q = [math.cos(theta / 2), *(math.sin(theta / 2) * axis)]
    r = rotation_from_quaternion(*q)
    np.testing.assert_allclose(r, rotation_from_axis_degrees(axis, 70), atol=1e-15)
    np.testing.assert_allclose(rotation_from_quaternion(*(-np.array(q))), r, atol=1e-15)
    np.testing.assert_allclose(rotation_from_quaternion(*(5 * np.array(q))), r, atol=1e-15)


def test_parse_quaternion_with_leading_minus():
    r = parse_quaternion("-0.7,0.1,0.7,0")
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(r, parse_quaternion("0.7,-0.1,-0.7,0"), atol=0)


@pytest.mark.parametrize("call", [
    lambda: rotation_from_quaternion(0, 0, 0, 0),
    lambda: rotation_from_quaternion(float("nan"), 0, 0, 1),
    lambda: parse_quaternion("1,0,0"),
    lambda: parse_quaternion("a,b,c,d"),
    lambda: rotation_from_axis_degrees([0, 0, 0], 10),
    lambda: rotation_from_axis_degrees("w", 10),
    lambda: rotation_from_axis_degrees("x", float("inf")),
    lambda: parse_turn("z"),
    lambda: parse_turn(":90"),
    lambda: parse_turn("z:ninety"),
    lambda: parse_turn("1,1:90"),
    lambda: parse_turn("q:90"),
])
def test_refusals(call):
    with pytest.raises(UsageError) as info:
        call()
    assert info.value.hint


@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda v: np.linalg.norm(v) > 1e-6))
def test_quaternions_give_proper_rotations(q):
    r = rotation_from_quaternion(*q)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)
    assert math.isclose(np.linalg.det(r), 1.0, abs_tol=1e-14)


@given(st.lists(st.floats(-10, 10), min_size=3, max_size=3).filter(lambda v: np.linalg.norm(v) > 1e-3),
       st.floats(-720, 720))
def test_axis_angle_fixes_its_axis(axis, deg):
    r = rotation_from_axis_degrees(axis, deg)
    u = np.array(axis) / np.linalg.norm(axis)
    np.testing.assert_allclose(r @ u, u, atol=1e-14)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-14)


@pytest.mark.parametrize("axis", ["x", "y", "z", [1.0, 1.0, 0.0]])
@pytest.mark.parametrize("degrees", [90, 180, 270, -90, 450, 30, 45])
def test_a_scene_turn_and_a_rotate_turn_are_one_rotation(axis, degrees):
    # One formula: a scene's {axis, degrees} goes through its quaternion, --rotate through
    # Rodrigues; quarter turns about the named axes are exact both ways (the scene used to be
    # off by 2e-16).
    from p3d_cli.constraints.values import rotation as scene_rotation
    from p3d_cli.geometry.rotation import quaternion_matrix

    q = scene_rotation({"axis": list(np.eye(3)["xyz".index(axis)]) if isinstance(axis, str) else axis,
                        "degrees": degrees}, "scene.yaml: bodies.a.rotation")
    from_scene = quaternion_matrix(q)
    from_cli = rotation_from_axis_degrees(axis, degrees)
    if isinstance(axis, str) and degrees % 90 == 0:
        assert np.array_equal(from_scene, from_cli)
        assert set(np.abs(from_cli).ravel().tolist()) <= {0.0, 1.0}
    else:
        assert np.abs(from_scene - from_cli).max() <= 4e-16
