"""Error-free float64 arithmetic on numpy arrays, and exact sums of float arrays.

The open-mesh boundary terms (``p3d_cli.mesh.boundary``) need sums far beyond float64's 53
bits; these are the building blocks (docs/method.md, "Open and non-manifold meshes"):

- ``two_sum`` (Knuth; Møller 1965): ``s + e == a + b`` exactly, ``s = fl(a + b)``.
- ``two_product`` (Dekker 1971, with Veltkamp's splitting; numpy has no fused multiply-add):
  ``p + e == a · b`` exactly, ``p = fl(a · b)``, as long as no product under- or overflows:
  the callers scale their inputs by a power of two to ``|x| <= 1`` first (overflow then cannot
  happen) and bound what underflow can lose (at most ``2**-1074`` per operation).
- ``rounded_sum``: a short sum of products of floats (a composed placement's entries), exact
  in Python integers and rounded once, with its rounding error.
- ``ExactSum``: the exact sum of many float arrays as a ``Fraction``. Each float is
  ``f · 2**e`` with ``|f| < 1`` an integer multiple of ``2**-53`` (``numpy.frexp``); its
  scaled mantissa ``f · 2**27`` is split into its floor (an integer below ``2**27`` in
  magnitude) and the rest (a multiple of ``2**-26`` in ``[0, 1)``), and each part is summed per
  (quantity, exponent) bin with ``numpy.bincount``. The float bins are moved into Python
  integers before any of them can hold ``2**25`` values, so every float bin stays below
  ``2**52`` on its grid and the float64 accumulation of ``bincount`` is exact. This is
  the "long accumulator" idea (Kulisch; Shewchuk 1997 and Ogita, Rump and Oishi 2005 give
  the error-free transformations behind ``two_sum``/``two_product``), vectorised by exponent.

References: T. J. Dekker, "A floating-point technique for extending the available
precision", Numer. Math. 18, 1971; J. R. Shewchuk, "Adaptive precision floating-point
arithmetic and fast robust geometric predicates", Discrete Comput. Geom. 18, 1997;
T. Ogita, S. M. Rump, S. Oishi, "Accurate sum and dot product", SIAM J. Sci. Comput. 26, 2005.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

#: Veltkamp's splitter for float64: 2**27 + 1.
_SPLITTER = 134217729.0
#: Unit roundoff of float64.
UNIT = 2.0 ** -53
#: The smallest positive (subnormal) float64.
TINY = 2.0 ** -1074
#: ``numpy.frexp`` exponents of finite float64 lie in [-1073, 1024].
_E_MIN, _E_SPAN = -1073, 2098
#: Values added between two moves of the float bins into integers (see the module notes).
_MAX_PENDING = 1 << 25
#: Values per bincount call (bounds the temporaries).
_STEP = 1 << 20
_LOW_BITS = 26


def two_sum(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(s, e)`` with ``s = fl(a + b)`` and ``s + e == a + b`` exactly (no branch on sizes)."""
    s = a + b
    bb = s - a
    e = (a - (s - bb)) + (b - bb)
    return s, e


def split(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Veltkamp's split ``a == hi + lo`` exactly, each half of at most 26 significant bits
    (``|a|`` below ``2**996``, or ``_SPLITTER · a`` overflows)."""
    c = _SPLITTER * a
    hi = c - (c - a)
    return hi, a - hi


def two_product(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(p, e)`` with ``p = fl(a · b)`` and ``p + e == a · b`` exactly (Dekker 1971), barring
    underflow of the partial products (each then loses at most ``2**-1075``)."""
    p = a * b
    ah, al = split(a)
    bh, bl = split(b)
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


def cascaded_sums(values: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Row sums of ``values`` ``(k, n)`` to about twice float64's precision, cheaply.

    A pairwise tree of ``two_sum``: each level adds the two halves of the row with error-free
    sums and sets the errors aside; the errors are added in plain float64 (Ogita, Rump and
    Oishi's ``Sum2``, vectorised as a tree). Returns ``(high, low, factor)``: each row sum is
    ``high + low`` within ``factor · ε² · Σ|values|`` (``ε = 2**-53``): ``L = ceil(log2 n)``
    levels, each setting aside errors of at most ``ε`` of its (non-growing, to first order)
    absolute sum, added by ``numpy.sum`` (at most ``log2 n + 12`` roundings deep, see
    ``boundary_terms.Locals``) and then into ``low`` (``L`` more).
    """
    x = values
    k, n = x.shape
    low = np.zeros(k)
    while x.shape[1] > 1:
        if x.shape[1] % 2:
            x = np.concatenate([x, np.zeros((k, 1))], axis=1)
        half = x.shape[1] // 2
        x, error = two_sum(x[:, :half], x[:, half:])
        low += error.sum(axis=1)
    high = x[:, 0] if n else np.zeros(k)
    return high, low, cascade_factor(n)


def cascade_factor(n: int) -> float:
    """``cascaded_sums``' error factor for rows of ``n`` values: ``L = ceil(log2 n)`` levels."""
    levels = max(n - 1, 0).bit_length()
    return 1.02 * levels * (math.log2(max(n, 1)) + 12 + levels)


def product_of_splits(a: np.ndarray, a_split: tuple, b: np.ndarray, b_split: tuple) -> tuple[np.ndarray, np.ndarray]:
    """``two_product(a, b)`` given ``split(a)`` and ``split(b)`` (a value split once serves
    all its products: half the cost of ``two_product`` when each value is used many times)."""
    p = a * b
    ah, al = a_split
    bh, bl = b_split
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    return p, e


class ExactSum:
    """Exact running sums of ``count`` quantities, fed float64 arrays.

    ``add(values, rows)`` adds each row of ``values`` (``(k, m)``, finite) to the quantity
    ``rows[r]``; ``totals()`` returns the exact sums as ``Fraction``. ``binner``, when given, is
    a compiled ``binner(values, offsets, high, low)`` that adds each value's two parts to the
    float bins as ``add`` does (row ``r``'s bins from ``offsets[r]``, by exponent): the same
    bins, since each bin's sum is exact in any order.
    """

    def __init__(self, count: int, binner=None) -> None:
        self.count = count
        self._binner = binner
        self._high = np.zeros(count * _E_SPAN, dtype=object)
        self._low = np.zeros(count * _E_SPAN, dtype=object)
        self._pending_high = np.zeros(count * _E_SPAN)
        self._pending_low = np.zeros(count * _E_SPAN)
        self._pending = 0          # values per bin at most, since the last flush
        self._touched = np.zeros(count * _E_SPAN, dtype=bool)

    def add(self, values: np.ndarray, rows: np.ndarray) -> None:
        """Add ``values`` ``(k, m)`` row by row to the quantities ``rows`` ``(k,)`` (int)."""
        k, m = values.shape
        if m == 0:
            return
        step = max(1, _STEP // k)
        for start in range(0, m, step):
            part = values[:, start:start + step]
            # Worst case every value since the last flush landed in one bin.
            if self._pending + part.size > _MAX_PENDING:
                self._flush()
            if self._binner is not None:
                offsets = np.asarray(rows, dtype=np.int64) * _E_SPAN - _E_MIN
                self._binner(np.ascontiguousarray(part, dtype=np.float64), offsets, self._pending_high,
                             self._pending_low)
                self._pending += part.size
                continue
            # f = fraction · 2**27 has 27 integer and 26 fraction bits: its floor and the rest
            # (a multiple of 2**-26 in [0, 1)) are exact, all in float64 (no integer casts).
            fraction, exponent = np.frexp(part)
            fraction *= 2.0 ** 27
            high = np.floor(fraction)
            fraction -= high
            bins = exponent.astype(np.intp)
            bins += (np.asarray(rows, dtype=np.intp) * _E_SPAN - _E_MIN)[:, None]
            bins = bins.reshape(-1)
            size = self.count * _E_SPAN
            self._pending_high += np.bincount(bins, weights=high.reshape(-1), minlength=size)
            self._pending_low += np.bincount(bins, weights=fraction.reshape(-1), minlength=size)
            self._pending += part.size

    def _flush(self) -> None:
        """Move the float bins (exact integers below 2**53) into the Python-int bins."""
        if self._pending:
            for pending, exact in ((self._pending_high, self._high), (self._pending_low, self._low)):
                hit = np.flatnonzero(pending)
                # High sums are integers, low sums multiples of 2**-26: both exact as scaled.
                scale = 1 if pending is self._pending_high else 1 << _LOW_BITS
                exact[hit] += np.array([int(x * scale) for x in pending[hit].tolist()], dtype=object)
                self._touched[hit] = True
                pending[:] = 0.0
        self._pending = 0

    def totals(self) -> list[Fraction]:
        """The exact sum of everything added to each quantity."""
        self._flush()
        out = []
        for q in range(self.count):
            at = slice(q * _E_SPAN, (q + 1) * _E_SPAN)
            high, low = self._high[at], self._low[at]
            # The bins ever given a nonzero value (comparing every object bin with 0 cost more
            # than the sums; a bin that came back to 0 adds nothing).
            hit = [int(b) for b in np.flatnonzero(self._touched[at])]
            if not hit:
                out.append(Fraction(0))
                continue
            # Bin b holds mantissas of exponent e = b + _E_MIN: value = mantissa · 2**(e - 53).
            lowest = hit[0]
            # mantissa · 2**-53 = fraction: high · 2**26 + low (low already scaled by 2**26)
            total = sum(((high[b] << _LOW_BITS) + low[b]) << (b - lowest) for b in hit)
            out.append(Fraction(total) * Fraction(2) ** (lowest + _E_MIN - 53))
        return out


def rounded_sums(sums) -> tuple[np.ndarray, np.ndarray]:
    """``rounded_sum`` of each entry of a list (or a list of lists) of product lists: the
    values and their roundings as arrays."""
    pairs = np.array([[rounded_sum(terms) for terms in row] for row in sums]
                     if isinstance(sums[0][0], list) else [rounded_sum(terms) for terms in sums])
    return pairs[..., 0].copy(), pairs[..., 1].copy()


def rounded_sum(terms) -> tuple[float, float]:
    """``Σ Π term`` for ``terms``, a list of tuples of floats (products of a few factors),
    computed exactly and rounded once, and ``|rounded - exact|`` rounded up (0 when exact).

    Every finite float is an integer times a power of two, so the sum is a Python integer over
    a power of two; Python's integer division rounds it correctly (subnormals too). A non-finite
    factor gives the float sum with an infinite error.
    """
    num, shift = 0, 0
    try:
        for term in terms:
            n, e = 1, 0
            for x in term:
                a, b = float(x).as_integer_ratio()
                n *= a
                e += b.bit_length() - 1
            if n == 0:
                continue
            if e > shift:
                num <<= e - shift
                shift = e
            num += n << (shift - e)
    except (OverflowError, ValueError):   # inf or nan
        return float(sum(math.prod(t) for t in terms)), math.inf
    if num == 0:
        return 0.0, 0.0
    den = 1 << shift
    try:
        value = num / den
    except OverflowError:
        return (math.inf if num > 0 else -math.inf), math.inf
    a, b = value.as_integer_ratio()
    diff = abs(num * b - a * den)
    if diff == 0:
        return value, 0.0
    return value, math.nextafter(diff / (den * b), math.inf)
