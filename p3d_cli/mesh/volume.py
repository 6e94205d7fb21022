"""The signed volume of a triangle soup alone, bit-identical to ``triangle_moments(t).volume``.

``p3d check`` reports only the volume, so it computes only the determinant row of the
divergence-theorem sums (``integrals.tetra_terms``: ``D = p1 · ((p2 - p1) × (p3 - p1))``
about the same local origin, with the same operations in the same order) and its rounding
bound, in the same blocks of ``BLOCK`` faces summed pairwise and then with ``math.fsum``.
The other nine sums are a quarter of the work each; skipping them changes no bit of the
volume (the tests compare the two).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.integrals import determinants, volume_from

#: Faces per summed block: ``triangle_moments``' default block.
BLOCK = 65536
_UNIT_ROUNDOFF = np.finfo(np.float64).eps / 2
_SMALLEST = 2.0 ** -1074


class SignedVolume:
    """Running signed volume about ``origin``; feed blocks of any size in file order.

    ``block`` faces are summed pairwise at a time (``BLOCK``: as ``triangle_moments``); with
    ``block=None`` each fed block is summed on its own, as the one-pass analysis of
    ``p3d props`` sums the blocks a ``MeshSource`` yields, so that ``p3d check`` fed the same
    blocks about the same origin gets the same bits.
    """

    def __init__(self, origin: np.ndarray, block: int | None = BLOCK) -> None:
        self.origin = np.asarray(origin, dtype=np.float64).reshape(3)
        self._block = block
        self._det = np.empty(block or 0)
        self._magnitude = np.empty(block or 0)
        self._filled = 0
        self._totals: list[float] = []
        self._abs_totals: list[float] = []
        self._count = 0
        self._longest = 1

    def add(self, triangles: np.ndarray) -> None:
        """Add ``(k, 3, 3)`` triangles (float32 or float64)."""
        self.add_columns(columns(triangles))

    def add_columns(self, cols: np.ndarray) -> None:
        """Add triangles as ``(3, 3, k)`` float64 columns (``columns.columns``); shifted in
        place to the origin."""
        cols -= self.origin[None, :, None]
        start, k = 0, cols.shape[2]
        if self._block is None:
            if k:
                self._det, self._magnitude = np.empty(k), np.empty(k)
                determinants(cols[0], cols[1], cols[2], self._det, self._magnitude)
                self._filled = k
                self._flush()
            return
        while start < k:
            take = min(self._block - self._filled, k - start)
            at = slice(self._filled, self._filled + take)
            block = cols[:, :, start:start + take]
            determinants(block[0], block[1], block[2], self._det[at], self._magnitude[at])
            self._filled += take
            start += take
            if self._filled == self._block:
                self._flush()

    def add_sums(self, det: float, magnitude: float, k: int) -> None:
        """Add a block of ``k`` faces summed elsewhere (``p3d_cli.mesh.kernels``): the pairwise
        sums of its ``D`` and of their magnitudes, as ``block=None`` sums a fed block."""
        self._flush()
        if k:
            self._totals.append(float(det))
            self._abs_totals.append(float(magnitude) * 1.01)
            self._count += k
            self._longest = max(self._longest, k)

    def _flush(self) -> None:
        k = self._filled
        if k:
            # As MomentSums: a block's terms summed pairwise, its magnitude bound times 1.01.
            self._totals.append(float(self._det[:k].sum()))
            self._abs_totals.append(float(self._magnitude[:k].sum()) * 1.01)
            self._count += k
            self._longest = max(self._longest, k)
        self._filled = 0

    def volume(self, extra: Fraction | None = None) -> float:
        """The volume, 0.0 when the sum is within its rounding bound of zero (as ``Moments``).

        ``extra``: exact ``6V`` terms to add first (an open mesh's boundary terms,
        ``p3d_cli.mesh.boundary.boundary_sums``), as ``MomentSums.moments`` adds them.
        """
        self._flush()
        if not self._totals and extra is None:
            return 0.0
        total = math.fsum(self._totals)
        abs_total = 0.0
        for value in self._abs_totals:      # the row-by-row sum of MomentSums.totals
            abs_total += value
        bound = ((20 + math.log2(self._longest)) * _UNIT_ROUNDOFF * abs_total
                 + 40 * self._count * _SMALLEST)
        return volume_from(total if extra is None else Fraction(total) + extra, bound)

