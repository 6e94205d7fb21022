"""The one number grammar of the text readers (OBJ, OFF, ASCII PLY, ASCII STL).

A number is decimal: ``[+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?``, and it
must be finite in float64. An index is ``[+-]? digits``. Python's ``float`` and ``int`` accept
more (``1_0``, ``inf``, ``nan``, surrounding spaces) and ``np.fromstring`` accepts other things
(as int64 it reads ``'- 3'`` as -3, ``'1 -'`` as ``1 0`` and saturates ``99999999999999999999``
to 2^63 - 1; as float64 it reads ``nan``, ``inf`` and overflows ``1e999`` to inf). The careful
parsers use ``to_float``/``to_int`` below; the fast paths use numpy and then reject, with the
checks below, every input on which numpy's reading could differ, so both paths accept the same
inputs and give the same numbers.
"""

from __future__ import annotations

import re

import numpy as np

__all__ = ["to_float", "to_int", "lone_sign", "saturated", "INT64_LIMITS", "fromstring"]

_FLOAT = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_INT = re.compile(rb"[+-]?[0-9]+")
#: int64 values numpy's integer parser saturates to: a text holding either is re-read carefully.
INT64_LIMITS = (np.iinfo(np.int64).min, np.iinfo(np.int64).max)

#: Maps digits and '.' to '0', signs to '-', everything else to ' ': a sign must be followed by
#: a digit or a point, so ``'- '`` or a final ``'-'`` in the mapped text is a lone sign.
_SIGN_TABLE = bytes(ord("0") if c in b"0123456789." else ord("-") if c in b"+-" else ord(" ")
                    for c in range(256))


def to_float(word: bytes) -> float:
    """``word`` as a float64 if it is a finite decimal number.

    Raises
    ------
    ValueError
        Not a decimal number (``1_0``, ``nan``, ``0x1p3``, ``1e``) or out of float64's range.
    """
    if not _FLOAT.fullmatch(word):
        raise ValueError(word)
    value = float(word)
    if value in (float("inf"), float("-inf")):
        raise ValueError(word)
    return value


def to_int(word: bytes) -> int:
    """``word`` as an integer (any size) if it is ``[+-]?digits``.

    Raises
    ------
    ValueError
        Anything else (``1_0``, ``1.0``, ``1e3``, ``+``).
    """
    if not _INT.fullmatch(word):
        raise ValueError(word)
    return int(word)


def lone_sign(text: bytes) -> bool:
    """True when a ``+`` or ``-`` in ``text`` is not followed by a digit or a point (numpy's
    integer parser would join it with the next number, or read it as 0)."""
    if b"-" not in text and b"+" not in text:
        return False
    mapped = text.translate(_SIGN_TABLE)
    return b"- " in mapped or mapped.endswith(b"-") or b"--" in mapped


def saturated(values: np.ndarray) -> bool:
    """True when an int64 array holds a value numpy's parser may have saturated to."""
    if not values.size:
        return False
    return bool(values.min() == INT64_LIMITS[0] or values.max() == INT64_LIMITS[1])


def fromstring(text: bytes, dtype) -> np.ndarray:
    """``np.fromstring(text, dtype, sep=" ")``, raising ``ValueError`` on text it cannot read to
    its end on every numpy p3d supports: numpy 2 raises, while numpy 1.x only warns
    (``DeprecationWarning``) and returns the numbers before the bad word, which the fast paths
    would take for the whole."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        try:
            return np.fromstring(text, dtype=dtype, sep=" ")
        except DeprecationWarning as exc:
            raise ValueError(str(exc)) from None
