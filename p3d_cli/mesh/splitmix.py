"""The splitmix64 finalizer (Steele, Lea and Flood, "Fast splittable pseudorandom number
generators", OOPSLA 2014), in place on uint64 arrays: the hash under the closed test's corner
and side keys, and under the compiled pass's balance of side directions."""

from __future__ import annotations

import numpy as np

_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31 = np.uint64(30), np.uint64(27), np.uint64(31)


def mix(z: np.ndarray, scratch: np.ndarray | None = None) -> np.ndarray:
    """The splitmix64 finalizer, in place on a uint64 array (wrapping arithmetic).

    ``scratch``, an array like ``z``, saves the three temporaries of the shifts.
    """
    if scratch is None:
        scratch = np.empty_like(z)
    z ^= np.right_shift(z, _S30, out=scratch)
    z *= _M1
    z ^= np.right_shift(z, _S27, out=scratch)
    z *= _M2
    z ^= np.right_shift(z, _S31, out=scratch)
    return z
