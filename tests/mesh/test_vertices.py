"""Exact vertex ids: the corner sort's confirmation pass by the kernels and by numpy.

Each test runs the same input through the compiled kernels and through the numpy code they
replace (``kernels.KERNELS`` set to None) and compares the results bit for bit; skipped where
the kernels are not built, except under CI, whose install compiles them (as
``test_kernels.py``).
"""

from __future__ import annotations


import numpy as np
import pytest

from helpers.kernels import bits, needs_kernels, numpy_road

pytestmark = needs_kernels


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_vertex_confirmation_is_the_numpy_codes(dtype):
    """``vertices.group_corners``' second pass by the kernels (``confirm`` and the volume's
    block sums): the same ids, points and volume bits as the numpy code, ``-0.0`` among them."""
    from p3d_cli.mesh.vertices import group_corners

    rng = np.random.default_rng(7)
    points = rng.integers(-3, 4, (400, 3)).astype(dtype) * dtype(0.25)
    faces = points[rng.integers(0, 400, (5000, 3))]
    faces[::7] *= -1.0                                  # -0.0 where 0.0 was
    blocks = lambda: (faces[lo:lo + 999] for lo in range(0, len(faces), 999))   # noqa: E731
    fast, slow = group_corners(blocks, len(faces)), numpy_road(group_corners, blocks, len(faces))
    assert np.array_equal(fast.ids, slow.ids) and np.array_equal(fast.first, slow.first)
    assert fast.points.dtype == slow.points.dtype and np.array_equal(bits(fast.points), bits(slow.points))
    assert bits(fast.volume) == bits(slow.volume)
