"""One assertion for the scene-format tests: a result equals the exact integrals of triangles."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.exact import exact_moments

RTOL = 1e-12


def assert_exact(result, triangles, factor: float = 1.0) -> None:
    """``result`` (a ``PropsResult``) equals the exact rational integrals of ``triangles``
    (float64 values, computed by the test itself), carried by a length ``factor`` (the file's
    unit in the result's unit: volume factor³, centre factor, inertia factor⁵)."""
    exact = exact_moments(np.asarray(triangles, dtype=np.float64))
    p = result.properties
    assert p.volume == pytest.approx(float(exact.volume) * factor ** 3, rel=RTOL)
    center = exact.center_float() * factor
    np.testing.assert_allclose(p.center_of_mass, center, rtol=RTOL, atol=RTOL * max(np.abs(center).max(), 1e-300))
    inertia = exact.inertia() * factor ** 5
    np.testing.assert_allclose(p.inertia, inertia, rtol=1e-10, atol=1e-10 * np.abs(inertia).max())
