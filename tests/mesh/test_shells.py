"""Shells: the listed shells' volumes and the components' roots, by the kernels and by numpy.

Each test runs the same input through the compiled kernels and through the numpy code they
replace (``kernels.KERNELS`` set to None) and compares the results bit for bit; skipped where
the kernels are not built, except under CI, whose install compiles them (as
``test_kernels.py``).
"""

from __future__ import annotations


import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers.kernels import SAME_BITS, bits, needs_kernels, numpy_road

pytestmark = needs_kernels


@pytest.mark.parametrize("n, dtype", [(1, np.float32), (129, np.float64), (65536, np.float32),
                                      (70001, np.float64), (140000, np.float32)])
def test_shell_volume_is_the_numpy_codes(n, dtype):
    """A listed shell's volume (``shells._volume``): the kernels' blocks give the bits of
    ``triangle_moments``, on blocks of 65,536 and their remainders."""
    from p3d_cli.mesh.shells import _volume

    rng = np.random.default_rng(n)
    faces = (rng.standard_normal((n, 3, 3)) * 10 + 3).astype(dtype)
    faces[..., 0] = np.maximum(faces[..., 0], 0)          # a bound of 0 beside a nonzero one
    if n % 2:
        faces[..., 2] = rng.choice([0.0, -0.0], faces.shape[:2])   # both bounds ±0: numpy's
    fast, slow = _volume(faces), numpy_road(_volume, faces)
    if SAME_BITS:
        assert bits(fast) == bits(slow)
    else:
        assert fast == pytest.approx(slow, rel=1e-12)


@given(st.integers(1, 300), st.integers(0, 600), st.integers(0, 2**32 - 1))
@settings(max_examples=60)
def test_components_roots_are_the_numpy_rounds(size, arcs, seed):
    """``shells.chunked_roots`` by the compiled union-find (arcs in pieces) gives the numpy
    rounds' array: every node's smallest fellow."""
    from p3d_cli.mesh.shells import chunked_roots

    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, size, arcs), rng.integers(0, size, arcs)
    pieces = lambda: ((a[lo:lo + 50], b[lo:lo + 50]) for lo in range(0, arcs, 50))   # noqa: E731
    fast, slow = chunked_roots(size, pieces), numpy_road(chunked_roots, size, pieces)
    assert np.array_equal(fast, slow)
