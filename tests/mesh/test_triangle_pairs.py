"""The pair classification of the self-intersection test against the rational oracle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.triangle_oracle import classify as oracle
from p3d_cli.geometry.predicates import in_safe_range
from p3d_cli.mesh.triangle_pairs import CONTACT, CROSSING, FOLD, NONE, OVERLAP, classify


def classified(pairs):
    """``classify`` on a list of ``(A, B)`` triangle pairs, vertices matched exactly."""
    pts = np.array([p for A, B in pairs for p in (*A, *B)], dtype=float)
    points, ids = np.unique(pts, axis=0, return_inverse=True)
    faces = ids.reshape(-1, 3)
    n = len(pairs)
    kind, edges = classify(points, faces, np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2), in_safe_range(points))
    return kind


def degenerate(T):
    T = np.array(T, dtype=object)
    u, v = T[1] - T[0], T[2] - T[0]
    return not any([u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]])


#: Configurations named in the issue, with their kinds.
CASES = {
    "crossing": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, -1), (1, 1, 1), (2, 2, 1)], CROSSING),
    "piercing through an edge": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, -1), (1, 1, 3), (5, 5, 1)], CROSSING),
    "vertex touching a face": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (1, 1, 3), (2, 3, 3)], NONE),
    "edge lying on a face": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (2, 1, 0), (1, 1, 3)], CONTACT),
    "shared edge, bent": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 0, 0), (1, -3, 2)], NONE),
    "shared edge, flat": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 0, 0), (1, -3, 0)], NONE),
    "fold": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(4, 0, 0), (0, 0, 0), (1, 3, 0)], FOLD),
    "shared vertex only": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (-4, 0, 1), (0, -4, 1)], NONE),
    "shared vertex, crossing": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (4, 4, 1), (4, 4, -1)], CROSSING),
    "coplanar overlap": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (5, 1, 0), (1, 5, 0)], OVERLAP),
    "coplanar, facing apart": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(1, 1, 0), (1, 5, 0), (5, 1, 0)], NONE),
    "coplanar, sharing a side": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 0, 0), (0, 4, 0), (-4, 0, 0)], NONE),
    "identical": ([(0, 0, 0), (4, 0, 0), (0, 4, 0)], [(0, 4, 0), (0, 0, 0), (4, 0, 0)], NONE),
}


@pytest.mark.parametrize("name", CASES)
@pytest.mark.parametrize("scale, offset", [(1.0, 0.0), (2.0 ** -30, 0.0), (1.0, 1e8), (2.0 ** 20, -3e12)])
def test_named_configurations(name, scale, offset):
    A, B, expected = CASES[name]
    A, B = (np.array(T, dtype=float) * scale + offset for T in (A, B))
    assert oracle(A.tolist(), B.tolist()) == expected
    assert classified([(A, B)])[0] == expected


def test_a_sliver_of_overlap_of_one_ulp_at_1e8_is_a_crossing():
    """Two faces that overlap by the smallest step the coordinates can make, far out."""
    x = 1e8
    step = np.spacing(x)
    A = [(x, 0, 0), (x + 4, 0, 0), (x, 4, 0)]
    B = [(x + 1, 1, -step), (x + 1, 1, 1), (x + 2, 2, 1)]       # dips one ulp below A's plane
    C = [(x + 1, 1, 0), (x + 1, 1, 1), (x + 2, 2, 1)]           # touches it
    assert [int(k) for k in classified([(A, B), (A, C)])] == [CROSSING, NONE]


coordinate = st.integers(-2, 2)


@st.composite
def triangle_pairs(draw):
    """Two non-degenerate triangles on a small integer grid (so sharing points, lines and
    planes often), optionally in one coordinate plane, under an exact scale and offset and
    an exact rotation (a signed permutation of the axes)."""
    pool = draw(st.lists(st.tuples(coordinate, coordinate, coordinate), min_size=6, max_size=6))
    pool = np.array(pool, dtype=float)
    if draw(st.booleans()):
        pool[:, draw(st.integers(0, 2))] = 0
    pick = draw(st.permutations(range(6)))
    A, B = pool[list(pick[:3])], pool[[pick[draw(st.integers(0, 5))] for _ in range(3)]]
    axes = draw(st.permutations(range(3)))
    signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3)))
    scale = 2.0 ** draw(st.integers(-20, 20))
    offset = draw(st.sampled_from([0.0, 1e8, -2.0 ** 45, 0.5]))
    A, B = (T[:, list(axes)] * signs * scale + offset for T in (A, B))
    return A, B


@given(triangle_pairs())
def test_classification_matches_the_oracle(pair):
    A, B = pair
    if degenerate(A.tolist()) or degenerate(B.tolist()):
        return
    assert classified([(A, B)])[0] == oracle(A.tolist(), B.tolist())


def test_many_random_pairs_in_one_call_match_the_oracle():
    """A dense sample of the same grid (thousands of pairs, every kind), vectorised at once."""
    rng = np.random.default_rng(11)
    pairs = []
    while len(pairs) < 4000:
        pool = rng.integers(-2, 3, (6, 3)).astype(float)
        if rng.random() < 0.5:
            pool[:, rng.integers(3)] = 0
        A, B = pool[rng.choice(6, 3, replace=False)], pool[rng.choice(6, 3, replace=False)]
        if not (degenerate(A.tolist()) or degenerate(B.tolist())):
            pairs.append((A * 2.0 ** -7 + 1e8, B * 2.0 ** -7 + 1e8))
    expected = np.array([oracle(A.tolist(), B.tolist()) for A, B in pairs])
    assert set(expected) == {NONE, CROSSING, OVERLAP, FOLD, CONTACT}
    assert (classified(pairs) == expected).all()
