"""Wedge (the half-cube x + y ≤ 0, docs/method.md): constants derived from the geometry, exactly."""

from fractions import Fraction as F

import numpy as np

import polyhedral_checks as checks
from p3d_cli.shapes import Wedge, wedge


def test_constants_equal_polyhedral_formulas_exactly():
    checks.check_constants_exact(wedge)


def test_constants_by_hand():
    # Half of the cube's volume; centroid of the cross-section triangle (-1/3, -1/3).
    assert wedge.VOLUME == 4
    assert wedge.CENTER == (F(-1, 3), F(-1, 3), 0)
    # Not Physics3D's: its integer division and wrong centre point are not reproduced.
    assert wedge.CENTRAL[0][1] == F(-4, 9)


def test_vertices_are_facts_md():
    assert wedge.VERTICES == ((-1, -1, -1), (-1, -1, 1), (1, -1, 1), (1, -1, -1), (-1, 1, -1), (-1, 1, 1))
    assert all(x + y <= 0 for x, y, _ in wedge.VERTICES)


def test_scaled_moments_match_exact_integrals():
    checks.check_scaled_moments(Wedge(1.0, 2.0, 3.0))
    checks.check_scaled_moments(Wedge(1e-3, 7.0, 1e5))


def test_surface_closed_and_outward():
    checks.check_surface(Wedge(1.0, 2.0, 3.0))


def test_inside():
    checks.check_inside(Wedge(0.5, 2.0, 3.0))
    w = Wedge(1.0, 2.0, 3.0)
    assert w.inside([[-1, -2, 0], [0.5, -1.0, 0], [1, -2, 3]]).all()       # on the slope / corners
    assert not w.inside([[0.5, -0.9, 0], [0, 0.1, 0]]).any()


def test_bounds():
    checks.check_bounds(Wedge(1.0, 2.0, 3.0))
    # Turned 180° about z the wedge occupies x + y ≥ 0 and still touches every face of its box.
    from p3d_cli.geometry.rotation import rotation_from_axis_degrees
    b = Wedge(1.0, 2.0, 3.0).bounds(rotation_from_axis_degrees("z", 45))
    s = np.sqrt(0.5)
    # Corners (1,-2), (-1,2), (-1,-2) turned by 45°: x' = s(x - y), y' = s(x + y).
    np.testing.assert_allclose(b.min, [-3 * s, -3 * s, -3], rtol=1e-15)
    np.testing.assert_allclose(b.max, [3 * s, s * 1, 3], rtol=1e-15)
