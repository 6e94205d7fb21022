"""Elliptic cylinder (the cylinder's exact generalisation): moments and closed-form bounds."""

import math

import numpy as np

import round_checks as checks
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import Cylinder, EllipticCylinder


def test_moments():
    m = EllipticCylinder(1.0, 2.0, 3.0).moments()
    assert math.isclose(m.volume, math.pi * 2 * 6, rel_tol=1e-15)
    # ∫x² = V a²/4, ∫z² = V h²/3.
    np.testing.assert_allclose(np.diag(m.central), m.volume * np.array([1 / 4, 4 / 4, 9 / 3]), rtol=1e-15)


def test_tessellation_converges_as_inverse_square():
    checks.check_convergence(EllipticCylinder(1.0, 5.0, 0.2))
    checks.check_richardson(EllipticCylinder(1.0, 5.0, 0.2))


def test_tessellation_closed_outward_inscribed():
    checks.check_tessellation_surface(EllipticCylinder(1.0, 5.0, 0.2))


def test_inside():
    checks.check_inside_fraction(EllipticCylinder(1.0, 5.0, 0.2))


def test_bounds_reduce_to_circular_cylinder():
    r = rotation_from_axis_degrees([1, -2, 0.5], 63)
    a = EllipticCylinder(1.5, 1.5, 2.0).bounds(r, [1, 2, 3])
    b = Cylinder(1.5, 2.0).bounds(r, [1, 2, 3])
    np.testing.assert_allclose(a.min, b.min, rtol=1e-14)
    np.testing.assert_allclose(a.max, b.max, rtol=1e-14)


def test_bounds_quarter_turn():
    b = EllipticCylinder(1.0, 2.0, 3.0).bounds(rotation_from_axis_degrees("x", 90))
    np.testing.assert_array_equal(b.max, [1, 3, 2])
