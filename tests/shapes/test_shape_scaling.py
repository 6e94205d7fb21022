"""Eq. 9 (and placement) on each class equals integrating the scaled, placed mesh directly.

Hypothesis draws scales from 1e-6 to 1e6 with aspect ratios up to 1e6, random rotations and
translations; the reference integrates the transformed triangles with triangle_moments.
"""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from helpers.exact import exact_moments
from helpers.strategies import rotations, scales
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.geometry.moments import scale_moments
from p3d_cli.geometry.placement import place_moments
from p3d_cli.geometry.rotation import rotation_from_quaternion
from p3d_cli.shapes import SHAPES


def stand_in(shape):
    return shape.triangles() if shape.polyhedral else shape.tessellate(24)


def assert_moments_close(got, want, rtol=1e-9):
    assert np.isclose(got.volume, want.volume, rtol=rtol)
    size = np.sqrt(np.abs(np.diag(want.central)))
    scale = np.outer(size, size)
    assert np.all(np.abs(got.central - want.central) <= rtol * scale + 1e-300)
    extent = np.sqrt(np.abs(np.diag(want.central)).max() / abs(want.volume))
    assert np.all(np.abs(got.center - want.center) <= rtol * (extent + np.abs(want.center)))


@given(st.sampled_from(sorted(SHAPES)), scales())
def test_eq9_equals_direct_integration_of_the_scaled_mesh(name, s):
    tris = stand_in(SHAPES[name]())
    via_eq9 = scale_moments(triangle_moments(tris), s)
    direct = triangle_moments(tris * s)
    assert_moments_close(via_eq9, direct)


@given(st.sampled_from(sorted(SHAPES)), scales())
def test_closed_form_scaled_equals_scaled_closed_form(name, s):
    shape = SHAPES[name]()
    placed = shape.scaled(s)
    assert_moments_close(scale_moments(shape.moments(), s), placed.moments(), rtol=1e-13)


@given(st.sampled_from(sorted(SHAPES)), scales(), rotations(),
       st.lists(st.floats(-10, 10), min_size=3, max_size=3))
def test_placement_equals_exact_integration_of_the_placed_mesh(name, s, r, t):
    """Scale, rotation and translation of the moments equal the placed mesh's exact integrals.

    The reference is tests/helpers/exact.py (rational arithmetic on the placed float coordinates):
    triangle_moments itself loses accuracy on rotated needles (its error bound covers it: below). The
    placed coordinates are rounded to float64, by up to eps·|coordinate|; relative to the
    part's thinnest extent that is eps·(largest coordinate / smallest scale), which bounds
    how closely the reference can agree (aspect ratios reach 1e6 here).
    """
    t = s.max() * np.array(t)                 # offsets in units of the part's size
    tris = stand_in(SHAPES[name]())
    placed = place_moments(triangle_moments(tris), s, r, t)
    exact = exact_moments((tris * s) @ r.T + t)
    rel = 1e-10 + 100 * np.finfo(float).eps * (s.max() + np.abs(t).max()) / s.min()
    assert np.isclose(placed.volume, float(exact.volume), rtol=rel)
    central = np.array([[float(x) for x in row] for row in exact.central])
    norm = np.abs(central).max()
    assert np.all(np.abs(placed.central - central) <= rel * norm)
    assert np.all(np.abs(placed.center - exact.center_float()) <= rel * (s.max() + np.abs(t)))


def test_direct_integration_of_a_rotated_needle_is_within_its_error_bound():
    tris = SHAPES["box"]().triangles() * [1, 1, 1e5]
    r = rotation_from_quaternion(0, 1, 1, 1)
    direct = triangle_moments(tris @ r.T)
    exact = exact_moments(tris @ r.T)
    assert abs(direct.volume - float(exact.volume)) <= direct.errors.volume
