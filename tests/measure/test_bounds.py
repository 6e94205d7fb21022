"""Placed bounds: exact for every class, never smaller than the shape and tight.

Hypothesis draws shapes, rotations, scales (1e-6 to 1e6, aspect ratios up to 1e6) and
translations. Dense surface samples of the placed solid must lie inside the box (never
smaller), and their extremes must reach it within the sampling resolution (tight). The
resolution is derived in the canonical frame: the extreme of a linear function w·u over a
round surface sampled at angular spacing δ falls short by at most |w|(1 - cos δ) ≤ |w| δ²/2.
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.strategies import rotations, scales

from p3d_cli.geometry.bounding import triangles_bounds
from p3d_cli.geometry.placement import placed_bounds
from p3d_cli.errors import UsageError
from p3d_cli.geometry.rotation import rotation_from_axis_degrees
from p3d_cli.shapes import SHAPES, Box, Cylinder, Sphere

GRID = 181          # samples per angle: spacing 2π/180 around, π/180 from pole to pole


def canonical_surface(shape):
    """Surface samples in the canonical frame, and the angular covering radius δ of the round
    parts (0 for polyhedra, whose vertices are sampled exactly)."""
    if shape.polyhedral:
        tris = type(shape)().triangles()
        rng = np.random.default_rng(0)
        w = rng.dirichlet([1, 1, 1], size=(len(tris), 50))
        return np.concatenate([tris.reshape(-1, 3), np.einsum("tkv,tvc->tkc", w, tris).reshape(-1, 3)]), 0.0
    phi = np.linspace(0, 2 * np.pi, GRID)
    dphi = phi[1]
    if shape.name in ("sphere", "ellipsoid"):
        theta = np.linspace(0, np.pi, GRID)
        t, p = np.meshgrid(theta, phi)
        pts = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
        # Great-circle distance to the nearest sample ≤ half a step in θ plus half in φ.
        return pts, theta[1] / 2 + dphi / 2
    if shape.name == "capsule":
        # Its own latitude-longitude surface, in the frame where placed.scale maps it back.
        theta = np.linspace(0, np.pi, GRID)
        t, p = np.meshgrid(theta, phi)
        ball = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], axis=-1).reshape(-1, 3)
        caps = ball * shape.r + np.where(ball[:, 2:] >= 0, 1.0, -1.0) * [0, 0, shape.h]
        return caps * shape.stretch / shape.scale, theta[1] / 2 + dphi / 2
    rim = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    z = np.linspace(-1, 1, 21)
    side = np.concatenate([np.hstack([rim, np.full((GRID, 1), zz)]) for zz in z])
    return side, dphi / 2


def check_placed(shape, s, r, t):
    b = placed_bounds(shape, s, r, t)
    placed = shape.scaled(s)
    pts_c, delta = canonical_surface(placed)
    world = (pts_c * placed.scale) @ r.T + t
    # Rounding allowance: a few ulps of each coordinate's magnitude.
    m = np.abs(r) * placed.scale
    mag = m.sum(axis=1) + np.abs(t)
    tol = 1e-13 * mag
    assert np.all(world >= b.min - tol), "bounds smaller than the shape (min)"
    assert np.all(world <= b.max + tol), "bounds smaller than the shape (max)"
    # Tight: |w| for axis i is at most the row norm of R S; δ²/2 of it is the sampling shortfall.
    shortfall = np.sqrt((m * m).sum(axis=1)) * delta * delta / 2 + tol
    assert np.all(world.min(axis=0) <= b.min + shortfall), "bounds not tight (min)"
    assert np.all(world.max(axis=0) >= b.max - shortfall), "bounds not tight (max)"


@given(st.sampled_from(sorted(SHAPES)), scales(), rotations(),
       st.lists(st.floats(-1e6, 1e6), min_size=3, max_size=3))
def test_bounds_contain_the_shape_and_are_tight(name, s, r, t):
    check_placed(SHAPES[name](), s, r, np.array(t))


@given(rotations(), scales())
def test_mesh_bounds_equal_projected_vertices(r, s):
    tris = Box(1, 2, 3).triangles()
    b = triangles_bounds(np.array_split(tris, 3), s, r, [1, 2, 3])
    pts = (tris.reshape(-1, 3) * s) @ r.T + [1, 2, 3]
    # (R S) p and R (S p) round differently: agree to a few ulps of the coordinates.
    tol = 1e-14 * (np.abs(r) @ (3 * s) + 3)
    assert np.all(np.abs(b.min - pts.min(axis=0)) <= tol)
    assert np.all(np.abs(b.max - pts.max(axis=0)) <= tol)


def test_examples():
    b = placed_bounds(Box(), [1, 2, 3], rotation_from_axis_degrees("z", 90), [10, 0, 0])
    np.testing.assert_array_equal(b.min, [8, -1, -3])
    np.testing.assert_array_equal(b.max, [12, 1, 3])
    b = placed_bounds(Sphere(2.0), None, rotation_from_axis_degrees("x", 33), [0, 0, 1])
    np.testing.assert_array_equal(b.max, [2, 2, 3])
    # A cylinder on its side: the closed form the Physics3D note left as a TODO (docs/method.md, "Rotated bounds"), |a_i| h + r sqrt(1 - a_i²).
    b = placed_bounds(Cylinder(1.0, 3.0), None, rotation_from_axis_degrees("y", 90))
    np.testing.assert_array_equal(b.max, [3, 1, 1])
    # Non-uniform --scale turns a sphere into the ellipsoid, whose bounds are exact too.
    b = placed_bounds(Sphere(1.0), [1, 2, 3], rotation_from_axis_degrees("x", 90))
    np.testing.assert_array_equal(b.max, [1, 3, 2])


# [-1, 1, 1] was refused until negative factors became mirrors (issue 13): see
# tests/geometry/test_placement_vocabulary.py.
@pytest.mark.parametrize("bad", [[0, 1, 1], [1, 1], [np.inf, 1, 1]])
def test_bad_scales_refused(bad):
    with pytest.raises(UsageError, match="^scale: "):
        placed_bounds(Box(), bad)
