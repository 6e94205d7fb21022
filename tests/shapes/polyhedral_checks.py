"""Checks shared by the box, wedge and corner tests (one class each imports them)."""

from __future__ import annotations

import numpy as np

from helpers.exact import exact_moments
from helpers.rational_oracle import directed_edges_pair_up, rational_moments
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.geometry.rotation import rotation_from_axis_degrees


def check_constants_exact(module) -> None:
    """The module's hand-derived constants equal the polyhedral formulas, exactly."""
    volume, center, central = rational_moments(module.VERTICES, module.FACES)
    assert module.VOLUME == volume
    assert tuple(module.CENTER) == center
    assert tuple(tuple(r) for r in module.CENTRAL) == central


def check_scaled_moments(shape) -> None:
    """Eq. 9 on the constants matches the scaled polyhedron's exact (dyadic) integrals."""
    m = shape.moments()
    exact = exact_moments(shape.triangles())
    assert np.isclose(m.volume, float(exact.volume), rtol=1e-15)
    np.testing.assert_allclose(m.center, exact.center_float(), rtol=1e-15, atol=1e-15 * shape.scale.max())
    want = np.array([[float(x) for x in row] for row in exact.central])
    np.testing.assert_allclose(m.central, want, rtol=1e-14, atol=1e-15 * np.abs(want).max())


def check_surface(shape) -> None:
    """Triangles are closed, outward-wound, and enclose the closed-form volume."""
    tris = shape.triangles()
    assert directed_edges_pair_up(tris)
    m = triangle_moments(tris)
    assert m.volume > 0
    assert np.isclose(m.volume, shape.moments().volume, rtol=1e-14)


def check_inside(shape, seed: int = 0) -> None:
    """Vertices and centre inside; points nudged out through each face outside; and the
    fraction of uniform points in the bounding box matches V / box volume."""
    verts = shape.vertices()
    assert shape.inside(verts).all()
    assert shape.inside(shape.moments().center).all()
    for tri in shape.triangles():
        n = np.cross(tri[1] - tri[0], tri[2] - tri[0])
        n /= np.linalg.norm(n)
        mid = tri.mean(axis=0)
        size = np.abs(verts).max()
        assert shape.inside(mid - 1e-9 * size * n).all()
        assert not shape.inside(mid + 1e-9 * size * n).any()
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1, 1, size=(200_000, 3)) * shape.scale
    frac = shape.inside(pts).mean()
    want = shape.moments().volume / (8 * np.prod(shape.scale))
    assert abs(frac - want) <= 5 * np.sqrt(want * (1 - want) / len(pts)) + 1e-12


def check_bounds(shape) -> None:
    """Unrotated: the box ±s; a quarter turn about z swaps x and y exactly; any rotation
    equals the projection of the triangles' corners."""
    b = shape.bounds()
    np.testing.assert_array_equal(b.min, -shape.scale)
    np.testing.assert_array_equal(b.max, shape.scale)
    turned = shape.bounds(rotation_from_axis_degrees("z", 90), [1.0, 2.0, 3.0])
    lo = np.array([-shape.sy, -shape.sx, -shape.sz]) + [1, 2, 3]
    hi = np.array([shape.sy, shape.sx, shape.sz]) + [1, 2, 3]
    # Which side each extreme lands on depends on the shape; the union box is what is exact.
    assert np.all(turned.min >= lo) and np.all(turned.max <= hi)
    r = rotation_from_axis_degrees([1, 2, 3], 37)
    pts = shape.triangles().reshape(-1, 3) @ r.T
    b = shape.bounds(r)
    np.testing.assert_allclose(b.min, pts.min(axis=0), rtol=0, atol=1e-15 * shape.scale.max())
    np.testing.assert_allclose(b.max, pts.max(axis=0), rtol=0, atol=1e-15 * shape.scale.max())
