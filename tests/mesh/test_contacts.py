"""The lines of contact's exact arithmetic (``p3d_cli.mesh.contacts``): points as integers on
one power-of-two grid, against their exact fractions."""

from __future__ import annotations

from fractions import Fraction

import numpy as np

from p3d_cli.mesh.contacts import IntegerPoints


def test_integer_points_are_the_fractions_on_one_grid():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(40, 3)) * 10.0 ** rng.integers(-12, 12, size=(40, 3))
    points[0] = [0.0, -0.0, 1.0]
    points[1] = [5e-324, -2.0**-1022, 2.0**1000]       # subnormals beside a huge coordinate
    points[2] = [-1.5, 3.0, -7.25]
    grid = IntegerPoints(points)
    unit = Fraction(2) ** grid.low
    for v in range(len(points)):
        assert [Fraction(x) * unit for x in grid[v]] == [Fraction(float(x)) for x in points[v]]
        assert all(isinstance(x, int) for x in grid[v])


def test_all_zero_points_are_zeros():
    grid = IntegerPoints(np.zeros((3, 3)))
    assert grid[1] == [0, 0, 0]
