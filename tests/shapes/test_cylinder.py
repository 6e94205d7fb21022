"""Cylinder: closed forms against refined tessellations, the closed-form rotated bounds."""

import math
from fractions import Fraction as F

import numpy as np

import round_checks as checks
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import Cylinder, EllipticCylinder, cylinder


def test_constants():
    assert cylinder.VOLUME_PER_PI == 2
    assert cylinder.CENTRAL_PER_PI[0][0] == F(1, 2) and cylinder.CENTRAL_PER_PI[2][2] == F(2, 3)
    r, h = 0.5, 2.0
    m = Cylinder(r, h).moments()
    V = math.pi * r * r * 2 * h
    assert math.isclose(m.volume, V, rel_tol=1e-15)
    # Textbook: Izz = m r²/2, Ixx = m (3 r² + L²)/12 with L = 2h.
    inertia = np.trace(m.central) * np.eye(3) - m.central
    np.testing.assert_allclose(np.diag(inertia), [V * (3 * r * r + 16) / 12] * 2 + [V * r * r / 2], rtol=4e-15)


def test_tessellation_converges_as_inverse_square():
    checks.check_convergence(Cylinder(1.5, 0.3))


def test_prism_volume_is_n_sin_2pi_over_n():
    n = 12
    from p3d_cli.mesh.integrals import triangle_moments
    v = triangle_moments(Cylinder().tessellate(n)).volume
    assert math.isclose(v, n * math.sin(2 * math.pi / n), rel_tol=1e-14)


def test_richardson_lands_on_closed_form():
    checks.check_richardson(Cylinder(0.7, 3.0))


def test_tessellation_closed_outward_inscribed():
    checks.check_tessellation_surface(Cylinder(2.0, 0.5))


def test_inside():
    c = Cylinder(1.0, 2.0)
    assert c.inside([[1, 0, 2], [0, -1, -2], [0.5, 0.5, 0]]).all()
    assert not c.inside([[0.8, 0.8, 0], [0, 0, 2.0001]]).any()
    checks.check_inside_fraction(c)


def test_bounds_closed_form():
    c = Cylinder(1.0, 2.0)
    b = c.bounds(rotation_from_axis_degrees("x", 90))          # axis now along -y
    np.testing.assert_array_equal(b.max, [1, 2, 1])
    a = np.array([1.0, 1.0, 1.0]) / math.sqrt(3)
    r = rotation_from_axis_degrees(np.cross([0, 0, 1], a), math.degrees(math.acos(a[2])))
    np.testing.assert_allclose(r[:, 2], a, rtol=1e-15)
    half = abs(a) * 2.0 + 1.0 * np.sqrt(1 - a * a)
    np.testing.assert_allclose(c.bounds(r).max, half, rtol=1e-15)


def test_scaled():
    assert Cylinder(1.0, 1.0).scaled([2, 2, 3]) == Cylinder(2.0, 3.0)
    assert Cylinder(1.0, 1.0).scaled([1, 2, 3]) == EllipticCylinder(1.0, 2.0, 3.0)
