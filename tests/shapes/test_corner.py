"""Corner (docs/method.md, "Wedge and corner vertices"): constants derived from the geometry, checked exactly."""

from fractions import Fraction as F

import numpy as np

import polyhedral_checks as checks
from p3d_cli.shapes import Corner, corner


def test_constants_equal_polyhedral_formulas_exactly():
    checks.check_constants_exact(corner)


def test_constants_by_hand():
    # 8/6, not Physics3D's integer-divided 1; centre the mean of the corners.
    assert corner.VOLUME == F(4, 3)
    assert corner.CENTER == (F(-1, 2),) * 3
    assert corner.CENTRAL[0][0] == F(1, 5) and corner.CENTRAL[0][1] == F(-1, 15)


def test_vertices_are_facts_md():
    assert corner.VERTICES == ((-1, -1, -1), (-1, -1, 1), (-1, 1, -1), (1, -1, -1))


def test_scaled_moments_match_exact_integrals():
    checks.check_scaled_moments(Corner(1.0, 2.0, 3.0))
    checks.check_scaled_moments(Corner(1e6, 1.0, 1e-6))


def test_surface_closed_and_outward():
    checks.check_surface(Corner(1.0, 2.0, 3.0))


def test_inside():
    checks.check_inside(Corner(0.5, 2.0, 3.0))
    c = Corner(1.0, 1.0, 1.0)
    assert c.inside([[-1, -1, -1], [-0.5, -0.5, -1.0]]).all()
    assert not c.inside([[0, 0, 0], [-0.4, -0.4, -0.1]]).any()


def test_bounds():
    checks.check_bounds(Corner(1.0, 2.0, 3.0))
    b = Corner().bounds(np.eye(3), [10.0, 0.0, 0.0])
    np.testing.assert_array_equal(b.min, [9.0, -1.0, -1.0])
    np.testing.assert_array_equal(b.max, [11.0, 1.0, 1.0])
