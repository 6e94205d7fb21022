"""Ellipsoid (the sphere's exact generalisation): eq. 9 moments and closed-form bounds."""

import math

import numpy as np

import round_checks as checks
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import Ellipsoid, Sphere


def test_moments():
    e = Ellipsoid(1.0, 2.0, 3.0)
    m = e.moments()
    assert math.isclose(m.volume, 4 / 3 * math.pi * 6, rel_tol=1e-15)
    np.testing.assert_allclose(np.diag(m.central), m.volume * np.array([1, 4, 9]) / 5, rtol=1e-15)
    s = Ellipsoid(2.0, 2.0, 2.0).moments()
    np.testing.assert_allclose(s.central, Sphere(2.0).moments().central, rtol=1e-15)


def test_tessellation_converges_as_inverse_square():
    checks.check_convergence(Ellipsoid(1.0, 3.0, 0.2))
    checks.check_richardson(Ellipsoid(1.0, 3.0, 0.2))


def test_tessellation_closed_outward_inscribed():
    checks.check_tessellation_surface(Ellipsoid(1.0, 3.0, 0.2))


def test_inside():
    checks.check_inside_fraction(Ellipsoid(1.0, 3.0, 0.2))


def test_bounds():
    e = Ellipsoid(1.0, 2.0, 3.0)
    np.testing.assert_array_equal(e.bounds().max, [1, 2, 3])
    b = e.bounds(rotation_from_axis_degrees("z", 90))
    np.testing.assert_array_equal(b.max, [2, 1, 3])
    # 45° about z: half-extent in x is sqrt((a cos)² + (b sin)²).
    b = e.bounds(rotation_from_axis_degrees("z", 45))
    assert math.isclose(b.max[0], math.sqrt(0.5 * 1 + 0.5 * 4), rel_tol=1e-15)
