"""The compiled kernels in tests: where they are tested, and how their sums are compared.

The kernel tests run the same input through the compiled kernels and through the numpy code
they replace, and compare the results bit for bit. They are skipped where the kernels are not
built, except under CI, whose install compiles them (there a missing kernel fails the tests).
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from p3d_cli.mesh import kernels

#: Mark a test (or a module, as ``pytestmark``) that needs the compiled kernels.
needs_kernels = pytest.mark.skipif(kernels.KERNELS is None and os.environ.get("CI") != "true",
                                   reason="the compiled kernels are not built here")

#: The kernels replay numpy's pairwise summation as numpy 2.3 and later do it; numpy before 2.3
#: cuts long reductions at other places, so its sums of more than a few thousand terms can differ
#: in the last bits. There the kernels and the numpy code are held to agree within the stated
#: error bound instead (both are exact sums rounded within it), and same-bits is not claimed.
SAME_BITS = np.lib.NumpyVersion(np.__version__) >= "2.3.0"


def numpy_road(function, *args, **kwargs):
    """``function(*args, **kwargs)`` with the compiled kernels switched off: the numpy code they
    replace, for the kernel tests to compare with."""
    saved = kernels.KERNELS
    kernels.KERNELS = None
    try:
        return function(*args, **kwargs)
    finally:
        kernels.KERNELS = saved


def bits(x) -> np.ndarray:
    """The float64 values' bit patterns, to compare sums bit for bit (``-0.0`` is not ``0.0``)."""
    return np.asarray(x, dtype=np.float64).view(np.uint64)
