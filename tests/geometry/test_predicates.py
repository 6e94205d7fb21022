"""Exact orientation signs: the float filter and the integer stage against rational arithmetic."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.geometry.predicates import (
    Planes,
    exact_orient3d,
    in_safe_range,
    orient2d,
    orient2d_about,
    orient2d_fraction,
    orient3d,
    orient3d_fraction,
)


def reference3(a, b, c, d):
    return np.array([orient3d_fraction(*p) for p in zip(a.tolist(), b.tolist(), c.tolist(), d.tolist())])


def near_coplanar(rng, k, offset=0.0, scale=1.0):
    """Points d rounded from exact points of the plane (a, b, c): mostly a hair off it, some on it."""
    a, b, c = (rng.random((k, 3)) * scale + offset for _ in range(3))
    s, t = rng.random((2, k, 1))
    d = a + s * (b - a) + t * (c - a)
    d[::5] = a[::5] + (b[::5] - a[::5]) * 0.5          # midpoints: often exactly on the plane
    d[1::7] = b[1::7]                                  # a vertex of the triangle: exactly zero
    return a, b, c, d


@pytest.mark.parametrize("offset, scale", [(0.0, 1.0), (1e8, 1.0), (-3e12, 1e3), (0.0, 1e-150), (1e150, 1e140)])
def test_orient3d_is_exact_near_and_on_the_plane(offset, scale):
    rng = np.random.default_rng(7)
    a, b, c, d = near_coplanar(rng, 3000, offset, scale)
    expected = reference3(a, b, c, d)
    assert 0 in expected and 1 in expected and -1 in expected
    safe = in_safe_range(np.concatenate([a, b, c, d]))
    assert (orient3d(a, b, c, d, safe) == expected).all()
    assert (orient3d(a, b, c, d, safe=False) == expected).all()


def test_a_float_evaluation_gets_some_of_those_signs_wrong():
    """The cases above are hard: plain float64 evaluation of the same determinant errs on them."""
    rng = np.random.default_rng(7)
    a, b, c, d = near_coplanar(rng, 3000, 1e8)
    naive = np.sign(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))
    assert (naive != reference3(a, b, c, d)).mean() > 0.05


def test_axis_aligned_planes_are_decided_by_the_filter_alone(monkeypatch):
    """A zero permanent proves a zero determinant: flat CAD faces never reach the integers."""
    import p3d_cli.geometry.predicates as predicates

    monkeypatch.setattr(predicates, "exact_orient3d", lambda *args: pytest.fail("exact stage used"))
    rng = np.random.default_rng(3)
    a, b, c, d = (rng.integers(-5, 5, (500, 3)).astype(float) * 0.1 + 7 for _ in range(4))
    for p in (a, b, c, d):
        p[:, 2] = 2.5                                   # one plane z = 2.5
    assert (Planes(a, b, c).side(d) == 0).all()


def test_outside_the_safe_range_everything_goes_to_the_integers():
    tiny = np.array([[0.0, 0.0, 0.0], [2.0 ** -600, 0, 0], [0, 2.0 ** -600, 0], [0, 0, 2.0 ** -600]])
    assert not in_safe_range(tiny)
    a, b, c, d = (tiny[i:i + 1] for i in range(4))
    assert orient3d(a, b, c, d, safe=False)[0] == 1          # a float64 evaluation underflows to 0
    assert float(np.dot(np.cross(b - a, c - a)[0], (d - a)[0])) == 0.0
    assert in_safe_range(np.array([[0.0, 1.0, -2.0 ** 199]]))


coordinate = st.one_of(st.integers(-3, 3).map(float), st.floats(-4, 4, allow_nan=False, width=32))


@given(st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=4, max_size=4),
       st.sampled_from([0.0, 1e8, -2.0 ** 40]), st.integers(-30, 30))
def test_orient3d_matches_fractions(points, offset, power):
    p = np.array(points) * 2.0 ** power + offset
    a, b, c, d = (p[i:i + 1] for i in range(4))
    expected = orient3d_fraction(*p.tolist())
    assert orient3d(a, b, c, d, in_safe_range(p))[0] == expected
    assert exact_orient3d(a, b, c, d)[0] == expected


@given(st.lists(st.tuples(coordinate, coordinate), min_size=3, max_size=3),
       st.sampled_from([0.0, 1e8, -2.0 ** 40]), st.integers(-30, 30))
def test_orient2d_matches_fractions(points, offset, power):
    p = np.array(points) * 2.0 ** power + offset
    a, b, c = (p[i:i + 1] for i in range(3))
    assert orient2d(a, b, c, in_safe_range(p))[0] == orient2d_fraction(*p.tolist())


@given(st.lists(st.tuples(coordinate, coordinate), min_size=3, max_size=12),
       st.sampled_from([0.0, 1e8, -2.0 ** 40]), st.integers(-30, 30))
def test_orient2d_about_gives_orient2d_of_each_c(points, offset, power):
    p = np.array(points) * 2.0 ** power + offset
    p[2::3] = p[0] + (p[1] - p[0]) * 0.5          # midpoints of a b: often exactly on the line
    c = p[2:]
    for safe in (in_safe_range(p), False):
        got = orient2d_about(p[0], p[1], c, safe)
        assert got.tolist() == [orient2d_fraction(p[0].tolist(), p[1].tolist(), q) for q in c.tolist()]
