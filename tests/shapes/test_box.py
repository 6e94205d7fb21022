"""Box: exact constants, scaled moments, surface, inside test, bounds."""

import numpy as np

import polyhedral_checks as checks
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import Box, box


def test_constants_equal_polyhedral_formulas_exactly():
    checks.check_constants_exact(box)


def test_scaled_moments_match_exact_integrals():
    checks.check_scaled_moments(Box(1.0, 2.0, 3.0))
    checks.check_scaled_moments(Box(1e-6, 1.0, 1e6))


def test_closed_form_values():
    m = Box(1.0, 2.0, 3.0).moments()       # a 2 × 4 × 6 block
    assert m.volume == 48.0
    # ∫x² dV over [-a, a] × ... = V a² / 3.
    np.testing.assert_allclose(np.diag(m.central), 48.0 * np.array([1, 4, 9]) / 3, rtol=1e-15)


def test_surface_closed_and_outward():
    checks.check_surface(Box(1.0, 2.0, 3.0))


def test_inside():
    checks.check_inside(Box(0.5, 2.0, 3.0))


def test_bounds():
    checks.check_bounds(Box(1.0, 2.0, 3.0))
    b = Box(1.0, 2.0, 3.0).bounds(rotation_from_axis_degrees("z", 90), [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(b.min, [-1.0, 1.0, 0.0])
    np.testing.assert_array_equal(b.max, [3.0, 3.0, 6.0])


def test_scaled_stays_a_box():
    assert Box(1, 2, 3).scaled([2, 2, 2]) == Box(2.0, 4.0, 6.0)
