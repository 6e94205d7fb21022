"""Capsule: closed forms against exact slice integrals, refined tessellations and Monte Carlo;
rotated bounds against the tessellation's vertices."""

from __future__ import annotations

import math
from fractions import Fraction as F

import numpy as np
import pytest

import round_checks as checks
import p3d_cli as p3d
from p3d_cli.errors import SpecError
from p3d_cli.geometry.rotation import rotation_from_rpy
from p3d_cli.shapes import Capsule, parse_spec


def _poly_mul(a, b):
    out = [F(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return out


def _integrate(poly, lo, hi):
    """Exact ∫ poly(z) dz over [lo, hi] for Fraction coefficients (constant term first)."""
    return sum(c * (hi ** (k + 1) - lo ** (k + 1)) / (k + 1) for k, c in enumerate(poly))


def slice_moments(r: F, h: F):
    """V/π, ∫x²/π, ∫z²/π by slicing along z: the disc of radius ρ(z) has area πρ², ∫x² over it
    πρ⁴/4; ρ² = r² on the cylinder, r² - (z - h)² on the top cap (the bottom mirrors it)."""
    z2 = [F(0), F(0), F(1)]
    cyl = [r * r]
    cap = [r * r - h * h, 2 * h, F(-1)]                  # r² - (z - h)² = r² - h² + 2hz - z²
    volume = _integrate(cyl, -h, h) + 2 * _integrate(cap, h, h + r)
    xx = (_integrate(_poly_mul(cyl, cyl), -h, h) + 2 * _integrate(_poly_mul(cap, cap), h, h + r)) / 4
    zz = _integrate(_poly_mul(cyl, z2), -h, h) + 2 * _integrate(_poly_mul(cap, z2), h, h + r)
    return volume, xx, zz


@pytest.mark.parametrize("r, h", [(F(1), F(1)), (F(7, 10), F(13, 10)), (F(3), F(1, 8)), (F(1, 50), F(40))])
def test_closed_form_equals_exact_slices(r, h):
    m = Capsule(float(r), float(h)).moments()
    volume, xx, zz = slice_moments(r, h)
    assert math.isclose(m.volume, float(volume) * math.pi, rel_tol=2e-15)
    np.testing.assert_allclose(np.diag(m.central), np.array([float(xx), float(xx), float(zz)]) * math.pi,
                               rtol=2e-15)
    assert not np.any(m.central - np.diag(np.diag(m.central))) and not np.any(m.center)


def test_tessellations_converge_to_the_closed_form():
    capsule = Capsule(0.7, 1.3)
    checks.check_convergence(capsule)
    checks.check_richardson(capsule)
    checks.check_tessellation_surface(capsule)


def test_inside_agrees_with_the_volume():
    checks.check_inside_fraction(Capsule(0.5, 2.0))
    checks.check_inside_fraction(Capsule(0.5, 2.0, (1.0, 3.0, 0.5)))


def test_stretched_capsule_is_eq9_of_the_capsule():
    """The stretched capsule's closed form equals its own tessellations' limit (Richardson)."""
    checks.check_richardson(Capsule(0.7, 1.3, (1.0, 2.0, 0.5)))


def test_monte_carlo_agrees():
    exact = p3d.props("capsule:1,2").properties
    mc = p3d.props("capsule:1,2", method="montecarlo", samples=200_000, seed=3)
    err = mc.uncertainty
    assert abs(mc.properties.volume - exact.volume) < 5 * err["volume"]
    assert np.all(np.abs(mc.properties.inertia - exact.inertia) < 5 * err["inertia"] + 1e-12)


@pytest.mark.parametrize("stretch", [(1.0, 1.0, 1.0), (0.5, 2.0, 3.0)])
@pytest.mark.parametrize("angles", [(0, 0, 0), (0.3, -1.1, 2.0), (math.pi / 2, 0, 0), (1, 1, 1)])
def test_rotated_bounds_are_the_minkowski_sum(angles, stretch):
    rotation = rotation_from_rpy(*angles)
    capsule = Capsule(0.4, 1.5, stretch)
    box = capsule.bounds(rotation, [1.0, -2.0, 3.0])
    # The fine tessellation is inscribed: its bounds approach the closed form from inside.
    verts = capsule.tessellate(512).reshape(-1, 3) @ rotation.T + [1.0, -2.0, 3.0]
    assert np.all(verts.min(axis=0) >= box.min - 1e-12) and np.all(verts.max(axis=0) <= box.max + 1e-12)
    np.testing.assert_allclose(verts.min(axis=0), box.min, atol=1e-4)
    np.testing.assert_allclose(verts.max(axis=0), box.max, atol=1e-4)


def test_spec_and_scaling():
    assert parse_spec("capsule:0.5,2") == Capsule(0.5, 2.0)
    assert parse_spec("capsule") == Capsule(1.0, 1.0)
    assert Capsule(0.5, 2.0).spec() == "capsule:0.5,2"
    assert Capsule(0.5, 2.0).scaled([2, 2, 2]) == Capsule(1.0, 4.0)
    with pytest.raises(SpecError, match="takes 2 numbers"):
        parse_spec("capsule:1")
    with pytest.raises(SpecError, match="not positive"):
        parse_spec("capsule:1,0")
    stretched = Capsule(0.5, 2.0).scaled([1, 1, 2])
    assert stretched == Capsule(0.5, 2.0, (1.0, 1.0, 2.0))
    assert stretched.scaled([2, 2, 1]) == Capsule(1.0, 4.0)          # uniform again: a capsule
    # A uniform scale of s multiplies V by s³ and C by s⁵, as eq. 9 does.
    a, b = Capsule(0.5, 2.0).moments(), Capsule(0.5, 2.0).scaled([3, 3, 3]).moments()
    assert math.isclose(b.volume, 27 * a.volume, rel_tol=1e-14)
    np.testing.assert_allclose(b.central, 243 * a.central, rtol=1e-14)
