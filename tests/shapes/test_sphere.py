"""Sphere: closed forms against refined tessellations, bounds ±r, inside test."""

import math
from fractions import Fraction as F

import numpy as np
import pytest

import round_checks as checks
from p3d_cli.errors import UsageError
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import Ellipsoid, Sphere, sphere


def test_constants():
    assert sphere.VOLUME_PER_PI == F(4, 3)
    assert sphere.CENTRAL_PER_PI[0][0] == F(4, 15)
    m = Sphere(2.0).moments()
    assert math.isclose(m.volume, 4 / 3 * math.pi * 8, rel_tol=1e-15)
    # Solid sphere: I = 2/5 m r², and I = tr(C) - C_xx = 2 C_xx.
    np.testing.assert_allclose(2 * np.diag(m.central), 0.4 * m.volume * 4, rtol=1e-15)


def test_tessellation_converges_as_inverse_square():
    checks.check_convergence(Sphere(1.5))


def test_richardson_lands_on_closed_form():
    checks.check_richardson(Sphere(0.7))


def test_tessellation_closed_outward_inscribed():
    checks.check_tessellation_surface(Sphere(2.0))
    checks.check_tessellation_surface(Sphere(2.0), n=3)


@pytest.mark.parametrize("bad", [0, 2, -4, 2.5, True])
def test_tessellate_refuses_bad_counts(bad):
    with pytest.raises(UsageError):
        Sphere().tessellate(bad)


def test_inside():
    s = Sphere(2.0)
    assert s.inside([[2, 0, 0], [0, 0, -2], [1, 1, 1]]).all()
    assert not s.inside([[2.0000001, 0, 0], [1.2, 1.2, 1.2]]).any()
    checks.check_inside_fraction(s)


def test_bounds_ignore_rotation():
    r = rotation_from_axis_degrees([1, 2, 3], 40)
    b = Sphere(2.0).bounds(r, [1, 2, 3])
    np.testing.assert_array_equal(b.min, [-1, 0, 1])
    np.testing.assert_array_equal(b.max, [3, 4, 5])


def test_scaled():
    assert Sphere(1.0).scaled([2, 2, 2]) == Sphere(2.0)
    assert Sphere(1.0).scaled([1, 2, 3]) == Ellipsoid(1.0, 2.0, 3.0)
