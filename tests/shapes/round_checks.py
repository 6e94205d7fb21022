"""Checks shared by the sphere, cylinder, ellipsoid and elliptic-cylinder tests.

The round shapes' constants are rational multiples of π; they are checked against refined
tessellations: the inscribed polyhedra's errors must fall as 1/N² (the ratio of successive
errors at N and 2N near 4), and Richardson extrapolation of two tessellations must land on
the closed form far closer than either tessellation does.
"""

from __future__ import annotations

import numpy as np

from helpers.rational_oracle import directed_edges_pair_up
from p3d_cli.mesh.integrals import triangle_moments


def tessellation_errors(shape, ns):
    """Relative errors of volume and central moments (max entry) of each tessellation."""
    m = shape.moments()
    out = []
    for n in ns:
        t = triangle_moments(shape.tessellate(n))
        out.append((abs(t.volume - m.volume) / m.volume,
                    np.abs(t.central - m.central).max() / np.abs(m.central).max()))
    return np.array(out)


def check_convergence(shape) -> None:
    ns = [16, 32, 64, 128, 256]
    errors = tessellation_errors(shape, ns)
    ratios = errors[:-1] / errors[1:]
    # O(1/N²): doubling N divides the error by about 4.
    assert np.all((ratios > 3.6) & (ratios < 4.4)), ratios
    # The constant: (2π)²/6 ≈ 6.6 for the prism, about 16.5 for the latitude-longitude sphere.
    assert np.all(errors[:, 0] * np.array(ns) ** 2 < 20)


def check_richardson(shape) -> None:
    """Eliminating the 1/N² term recovers the closed form to ~1/N⁴."""
    m = shape.moments()
    a, b = triangle_moments(shape.tessellate(256)), triangle_moments(shape.tessellate(512))
    volume = (4 * b.volume - a.volume) / 3
    central = (4 * b.central - a.central) / 3
    assert abs(volume - m.volume) / m.volume < 2e-7
    assert np.abs(central - m.central).max() / np.abs(m.central).max() < 2e-7


def check_tessellation_surface(shape, n: int = 12) -> None:
    tris = shape.tessellate(n)
    assert directed_edges_pair_up(tris)
    assert triangle_moments(tris).volume > 0
    # Inscribed: every vertex lies in the solid (within rounding of its surface).
    verts = tris.reshape(-1, 3)
    assert shape.inside(verts * (1 - 1e-12)).all()


def check_inside_fraction(shape, seed: int = 1) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-1, 1, size=(200_000, 3)) * shape.scale
    frac = shape.inside(pts).mean()
    want = shape.moments().volume / (8 * np.prod(shape.scale))
    assert abs(frac - want) <= 5 * np.sqrt(want * (1 - want) / len(pts))
