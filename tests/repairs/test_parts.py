"""The repair's parts on their own: the steps' grammar, boundary loops, hole triangulation and
the windings of patches."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.errors import UsageError
from p3d_cli.repairs.draft import draft_edges
from p3d_cli.repairs.fill import fill_hole
from p3d_cli.repairs.loops import boundary_loops
from p3d_cli.repairs.orient import patches
from p3d_cli.repairs.steps import resolve_steps

DEFAULT = ("degenerate", "duplicate", "orient", "holes", "outward")


def test_steps_grammar():
    assert resolve_steps(None, None) == DEFAULT
    assert resolve_steps(None, 1e-6) == ("weld",) + DEFAULT
    assert resolve_steps("orient,outward", None) == ("orient", "outward")
    assert resolve_steps(["outward", "orient"], None) == ("orient", "outward")     # always in order
    assert resolve_steps("-holes", None) == ("degenerate", "duplicate", "orient", "outward")
    assert resolve_steps("all,no-duplicate", None) == ("degenerate", "orient", "holes", "outward")
    assert resolve_steps("none", None) == ()
    with pytest.raises(UsageError, match="no repair step named 'fill'"):
        resolve_steps("fill", None)
    with pytest.raises(UsageError, match="needs a tolerance"):
        resolve_steps("weld,holes", None)
    with pytest.raises(UsageError, match="weld step is left out"):
        resolve_steps("holes", 1e-3)


def test_loops_touching_at_a_corner_are_cut_apart():
    # Two triangular holes through vertex 0, walked as one figure of eight.
    starts, ends = np.array([0, 3, 4, 0, 1, 2]), np.array([3, 4, 0, 1, 2, 0])
    loops, stray = boundary_loops(starts, ends)
    assert sorted(sorted(starts[loop].tolist()) for loop in loops) == [[0, 1, 2], [0, 3, 4]]
    for loop in loops:
        assert (ends[loop] == np.roll(starts[loop], -1)).all()        # each side runs into the next
    assert stray.size == 0


def test_a_boundary_that_does_not_close_is_stray():
    loops, stray = boundary_loops(np.array([0, 1, 2, 7]), np.array([1, 2, 0, 8]))
    assert [sorted(loop.tolist()) for loop in loops] == [[0, 1, 2]] and stray.tolist() == [3]


def polygon_area(points: np.ndarray) -> Fraction:
    xy = [(Fraction(float(x)), Fraction(float(y))) for x, y in points]
    return sum((x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(xy, xy[1:] + xy[:1])), Fraction(0)) / 2


def triangle_area(a, b, c) -> Fraction:
    (ax, ay), (bx, by), (cx, cy) = ([Fraction(float(v)) for v in p] for p in (a, b, c))
    return ((bx - ax) * (cy - ay) - (by - ay) * (cx - ax)) / 2


@given(st.integers(min_value=3, max_value=40), st.integers(min_value=0, max_value=2**32 - 1))
def test_ear_clipping_tiles_a_star_polygon_exactly(k, seed):
    """A star-shaped polygon with random radii (non-convex), in the plane z = 0.5: the fill's
    triangles all turn the loop's way and their areas sum exactly to the polygon's."""
    rng = np.random.default_rng(seed)
    # Evenly spread angles, each moved by less than half the spacing: star-shaped about 0.
    angle = (np.arange(k) + rng.uniform(-0.45, 0.45, k)) * 2 * np.pi / k
    radius = rng.uniform(0.2, 1.0, k)
    points = np.stack([radius * np.cos(angle), radius * np.sin(angle), np.full(k, 0.5)], axis=1)
    hole = fill_hole(points, np.arange(k))
    assert hole.filled and len(hole.triangles) == k - 2
    areas = [triangle_area(*points[t][:, :2]) for t in hole.triangles]
    assert all(a > 0 for a in areas)                       # none degenerate, all wound as the loop
    assert sum(areas) == polygon_area(points[:, :2])


def test_collinear_corners_give_no_degenerate_face():
    # A square with extra corners on two of its sides.
    points = np.array([[0, 0, 0], [0.5, 0, 0], [1, 0, 0], [1, 1, 0], [0.5, 1, 0], [0, 1, 0]], dtype=float)
    hole = fill_hole(points, np.arange(6))
    assert hole.filled
    assert all(triangle_area(*points[t][:, :2]) > 0 for t in hole.triangles)


def test_a_fill_never_repeats_an_edge_the_mesh_has():
    points = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    hole = fill_hole(points, np.arange(4), has_edge=lambda u, v: {u, v} == {0, 2})
    assert hole.filled and {1, 3} <= set(hole.triangles[0]) & set(hole.triangles[1])
    hole = fill_hole(points, np.arange(4), has_edge=lambda u, v: {u, v} in ({0, 2}, {1, 3}))
    assert not hole.filled and "non-manifold" in hole.reason


def test_loops_that_are_not_simple_or_have_no_area_are_left():
    crossing = np.array([[0, 0, 0], [4, 0, 0], [4, 2, 0], [1, -1, 0], [0, 2, 0]], dtype=float)
    assert fill_hole(crossing, np.arange(5)).reason == "seen along its normal the loop crosses itself"
    bow_tie = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]], dtype=float)     # no net area
    assert "encloses no area" in fill_hole(bow_tie, np.arange(4)).reason
    line = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0]], dtype=float)
    assert "encloses no area" in fill_hole(line, np.arange(3)).reason


def test_flatness_and_size_limits():
    bent = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0.2], [0, 1, 0]], dtype=float)
    hole = fill_hole(bent, np.arange(4))
    assert not hole.filled and hole.flatness == pytest.approx(0.05, rel=0.1)
    assert fill_hole(bent, np.arange(4), flatness=0.1).filled
    assert fill_hole(bent, np.arange(4), policy="any").filled
    square = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
    assert "larger than the limit" in fill_hole(square, np.arange(4), max_edges=3).reason


def mobius(n: int = 8) -> np.ndarray:
    """Vertex ids of a Moebius strip of ``n`` quads (two triangles each)."""
    top, bottom = list(range(n)), list(range(n, 2 * n))
    faces = []
    for i in range(n):
        a, b = top[i], bottom[i]
        c, d = (top[i + 1], bottom[i + 1]) if i + 1 < n else (bottom[0], top[0])     # the half twist
        faces += [[a, b, c], [b, d, c]]
    return np.array(faces)


def test_a_moebius_strip_cannot_be_wound_consistently():
    faces = mobius()
    found = patches(len(faces), draft_edges(faces))
    assert found.count == 1 and found.nonorientable.tolist() == [0] and not found.flip.any()


@given(st.sets(st.integers(min_value=0, max_value=47), max_size=23))
def test_the_fewer_faces_of_a_patch_are_the_ones_flipped(flipped):
    """A closed grid torus (48 faces) with fewer than half its faces turned round: exactly those
    are flipped back."""
    u, v = 4, 6
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    a, b = (i * v + j).ravel(), (((i + 1) % u) * v + j).ravel()
    c, d = (((i + 1) % u) * v + (j + 1) % v).ravel(), (i * v + (j + 1) % v).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    chosen = np.array(sorted(flipped), dtype=np.int64)
    faces[chosen] = faces[chosen][:, [0, 2, 1]]
    found = patches(len(faces), draft_edges(faces))
    assert np.flatnonzero(found.flip).tolist() == chosen.tolist()
