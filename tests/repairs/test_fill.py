"""Filling one loop: the simplicity test and ear clipping against exact oracles.

The simplicity test takes only the edge pairs whose boxes overlap and ear clipping only the
corners in an ear's box: here both are checked against a brute-force rational oracle on small
polygons whose corners sit on a coarse integer grid (collinear runs, repeated corners, touching
edges), and on round ones cut in blocks of a few pairs.
"""

from __future__ import annotations

from fractions import Fraction
from itertools import combinations

import numpy as np
import pytest

from p3d_cli.repairs import fill


def orient(a, b, c) -> int:
    value = (Fraction(b[0]) - Fraction(a[0])) * (Fraction(c[1]) - Fraction(a[1])) - \
        (Fraction(b[1]) - Fraction(a[1])) * (Fraction(c[0]) - Fraction(a[0]))
    return (value > 0) - (value < 0)


def on_segment(a, b, c) -> bool:
    return min(a[0], b[0]) <= c[0] <= max(a[0], b[0]) and min(a[1], b[1]) <= c[1] <= max(a[1], b[1])


def segments_meet(p, q, r, s) -> bool:
    d1, d2, d3, d4 = orient(p, q, r), orient(p, q, s), orient(r, s, p), orient(r, s, q)
    if d1 * d2 < 0 and d3 * d4 < 0:
        return True
    return ((d1 == 0 and on_segment(p, q, r)) or (d2 == 0 and on_segment(p, q, s))
            or (d3 == 0 and on_segment(r, s, p)) or (d4 == 0 and on_segment(r, s, q)))


def simple_oracle(corners) -> bool:
    """No two edges meet but consecutive ones, at their shared corner, without folding back."""
    k = len(corners)
    edges = [(corners[i], corners[(i + 1) % k]) for i in range(k)]
    for i in range(k):
        a, b, c = corners[i], corners[(i + 1) % k], corners[(i + 2) % k]
        if orient(a, b, c) == 0 and (b[0] - a[0]) * (c[0] - b[0]) + (b[1] - a[1]) * (c[1] - b[1]) <= 0:
            return False
    for i, j in combinations(range(k), 2):
        if j - i < 2 or (i == 0 and j == k - 1):
            continue
        if segments_meet(*edges[i], *edges[j]):
            return False
    return True


def twice_area(corners) -> Fraction:
    return sum((Fraction(corners[i][0]) * Fraction(corners[(i + 1) % len(corners)][1])
                - Fraction(corners[(i + 1) % len(corners)][0]) * Fraction(corners[i][1])
                for i in range(len(corners))), Fraction(0))


def polygons(seed: int, count: int):
    rng = np.random.default_rng(seed)
    for trial in range(count):
        k = int(rng.integers(3, 12))
        if trial % 2:
            corners = rng.integers(0, 4, size=(k, 2)).astype(np.float64)
        else:
            angles = np.sort(rng.uniform(0, 2 * np.pi, k))
            radii = rng.uniform(0.3, 1.0, k)
            corners = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        yield np.ascontiguousarray(corners)


@pytest.mark.parametrize("pairs", [1, 5, fill.PAIRS])
def test_simplicity_is_the_oracles(pairs, monkeypatch):
    monkeypatch.setattr(fill, "PAIRS", pairs)
    for corners in polygons(7, 400):
        assert fill._simple(corners, True) == simple_oracle(corners.tolist())


def test_ear_clipping_triangulates_every_simple_polygon():
    """k - 2 triangles of the loop's corners, each turning the loop's way with non-zero area,
    whose areas add up to the loop's (an exact tiling, given the polygon is simple)."""
    tried = 0
    for corners in polygons(11, 400):
        if not simple_oracle(corners.tolist()):
            continue
        k = len(corners)
        triangles = fill._ear_clipping(corners, np.arange(k), True, lambda a, b: False)
        assert triangles is not None and triangles.shape == (k - 2, 3)
        area = twice_area(corners.tolist())
        for t in triangles.tolist():
            assert twice_area([corners[v].tolist() for v in t]) * area > 0
        assert sum(twice_area([corners[v].tolist() for v in t]) for t in triangles.tolist()) == area
        tried += 1
    assert tried > 100



def round_loops(seed: int, count: int):
    """Loops of many corners on a circle, some pulled in (their ears' boxes hold many
    corners), some on a float32 grid far from the origin (the filter cannot decide some signs)."""
    rng = np.random.default_rng(seed)
    for trial in range(count):
        k = int(rng.integers(20, 200))
        angles = np.sort(rng.uniform(0, 2 * np.pi, k))
        radii = rng.uniform(0.5, 1.0, k) if trial % 3 else np.ones(k)
        corners = np.stack([radii * np.cos(angles), radii * np.sin(angles)], axis=1)
        if trial % 2:
            corners = (1e4 + corners).astype(np.float32).astype(np.float64)
        yield np.ascontiguousarray(corners)


@pytest.mark.parametrize("looped", [0, 10**9])
def test_ear_clipping_is_the_same_on_every_road(looped, monkeypatch):
    """The compiled corner test, the numpy one and the one-corner-at-a-time loop clip the same
    ears (exact signs on every road), an existing edge passed over on each."""
    from helpers.kernels import numpy_road

    monkeypatch.setattr(fill, "LOOPED", looped)
    tried = 0
    for corners in list(polygons(13, 200)) + list(round_loops(5, 30)):
        if not fill._simple(corners, True):       # the oracle's answer (above), faster
            continue
        k = len(corners)
        for has_edge in (lambda a, b: False, lambda a, b, k=k: {a, b} == {1, k - 1}):
            compiled = fill._ear_clipping(corners, np.arange(k), True, has_edge)
            plain = numpy_road(fill._ear_clipping, corners, np.arange(k), True, has_edge)
            assert (compiled is None) == (plain is None)
            if compiled is not None:
                assert compiled.tolist() == plain.tolist()
                tried += 1
    assert tried > 100


def _same_hole(a: fill.Hole, b: fill.Hole) -> None:
    assert (a.vertices == b.vertices).all() and a.edges == b.edges and a.reason == b.reason
    for x, y in zip(a.centre + (a.size, a.flatness), b.centre + (b.size, b.flatness)):
        assert x == y or (x != x and y != y), (a, b)          # bit for bit, nan as nan
    assert (a.triangles is None) == (b.triangles is None)
    if a.triangles is not None:
        assert a.triangles.dtype == b.triangles.dtype and (a.triangles == b.triangles).all()
    assert a.projected == b.projected and a.replaced is None and b.replaced is None


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("policy,flatness,max_edges", [("flat", fill.FLATNESS, fill.MAX_EDGES), ("flat", 0.0, 1000),
                                                       ("flat", 1e-3, 2), ("any", 1e-3, 2)])
def test_three_corner_loops_together_are_each_alone(dtype, policy, flatness, max_edges):
    """``fill_triangles`` gives every loop the ``Hole`` that ``fill_hole`` gives it alone: on
    random triangles far from the origin and near it, slivers, collinear corners, repeated
    corners and zero-area ones; with a zero flatness limit (rounding makes some loops "not
    flat") and a size limit below three edges."""
    rng = np.random.default_rng(7)
    points = [rng.normal(size=(300, 3)), rng.normal(size=(300, 3)) * 1e-3 + 1e4,
              np.outer(rng.normal(size=60), [1.0, 2.0, 3.0]),                  # all on one line
              rng.integers(-2, 3, size=(60, 3)).astype(float)]                # coarse grid: repeats, lines
    sliver = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-12, 0.0]])
    p = np.concatenate(points + [sliver]).astype(dtype)
    m = len(p)
    loops = np.concatenate([rng.integers(0, m, size=(400, 3)),                # repeated ids too
                            np.arange(600).reshape(-1, 3),
                            rng.integers(600, 660, size=(40, 3)), rng.integers(660, 720, size=(80, 3)),
                            [[m - 3, m - 2, m - 1], [5, 5, 5]]])
    together = fill.fill_triangles(p, loops, policy=policy, flatness=flatness, max_edges=max_edges)
    alone = [fill.fill_hole(p, loop, policy=policy, flatness=flatness, max_edges=max_edges) for loop in loops]
    assert len(together) == len(loops)
    for a, b in zip(together, alone):
        _same_hole(a, b)
    reasons = {h.reason for h in alone}
    assert fill.NO_AREA in reasons                                  # the cases were met
    if max_edges == 2 and policy == "flat":
        assert any(r and r.startswith("larger than the limit") for r in reasons)
    else:
        assert None in reasons
    if flatness == 0.0:
        assert any(r and r.startswith("not flat") for r in reasons)
    assert fill.fill_triangles(p, np.zeros((0, 3), dtype=np.int64)) == []
