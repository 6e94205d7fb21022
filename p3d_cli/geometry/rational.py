"""Exact 3-vectors of ``Fraction``s: the few operations the rare exact paths use."""

from __future__ import annotations

from fractions import Fraction


def exact(point) -> list[Fraction]:
    """A point's float coordinates as exact fractions."""
    return [Fraction(float(x)) for x in point]


def sub(a, b) -> list:
    return [x - y for x, y in zip(a, b)]


def cross(a, b) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def sign(x) -> int:
    return (x > 0) - (x < 0)
