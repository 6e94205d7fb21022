"""The fast topology against a plain-Python oracle, and each fast path against its slow twin.

The oracle matches vertices with a dict of exact coordinate tuples, groups edges in a dict,
walks shells and fans by breadth-first search and decides zero area with fractions.Fraction:
nothing shared with the vectorised code.
"""

from __future__ import annotations

from collections import defaultdict
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.meshes import cube_triangles
import p3d_cli.mesh.fans as fans
import p3d_cli.mesh.vertices as vertices
from p3d_cli.mesh.edges import group_edges
from p3d_cli.mesh.faces import duplicate_faces
from p3d_cli.mesh.columns import local_origin
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.mesh.topology import _array_blocks, topology
from p3d_cli.mesh.vertices import group_corners
from p3d_cli.mesh.volume import SignedVolume

KEYS = ("vertices", "edges", "boundary_edges", "nonmanifold_edges", "misoriented_edges",
        "nonmanifold_vertices", "zero_area_faces", "faces_with_repeated_vertex", "duplicate_faces",
        "shells")


def _components(nodes, links):
    seen, count = {}, 0
    for start in nodes:
        if start in seen:
            continue
        seen[start], stack = count, [start]
        while stack:
            for y in links[stack.pop()]:
                if y not in seen:
                    seen[y] = count
                    stack.append(y)
        count += 1
    return seen, count


def oracle(t) -> dict:
    """Every count of ``TopologyReport``, the slow and obvious way."""
    n = len(t)
    vid: dict = {}
    ids = [[vid.setdefault(tuple(float(x) + 0.0 for x in p), len(vid)) for p in face] for face in t]
    uses = defaultdict(list)                       # edge -> [(face, forward)]
    for f, (a, b, c) in enumerate(ids):
        for s, e in ((a, b), (b, c), (c, a)):
            if s != e:
                uses[(min(s, e), max(s, e))].append((f, s < e))
    counts = [len(u) for u in uses.values()]
    links = defaultdict(set)
    for u in uses.values():
        for f, _ in u:
            links[f] |= {g for g, _ in u if g != f}
    _, shells = _components(range(n), links)
    # Fans: corners (f, k) at each vertex, joined across edges used by exactly two faces and
    # between equal corners of one face; point faces' corners are left out.
    corner_links = defaultdict(set)
    for (lo, hi), u in uses.items():
        if len(u) == 2:
            (f, _), (g, _) = u
            for x in (lo, hi):
                for a in [(f, k) for k in range(3) if ids[f][k] == x]:
                    for b in [(g, k) for k in range(3) if ids[g][k] == x]:
                        corner_links[a].add(b)
                        corner_links[b].add(a)
    for f, face in enumerate(ids):
        for i in range(3):
            for j in range(3):
                if i != j and face[i] == face[j]:
                    corner_links[(f, i)].add((f, j))
    live = [(f, k) for f in range(n) for k in range(3) if len(set(ids[f])) > 1]
    label, _ = _components(live, corner_links)
    fan_sets = defaultdict(set)
    for (f, k), lab in label.items():
        fan_sets[ids[f][k]].add(lab)
    on_bad = {x for e, u in uses.items() if len(u) > 2 for x in e}
    nonmanifold = sum(1 for v, s in fan_sets.items() if len(s) > 1 and v not in on_bad)
    seen, dups = set(), 0
    for face in ids:
        key = tuple(sorted(face))
        dups += key in seen
        seen.add(key)
    return dict(vertices=len(vid), edges=len(uses), boundary_edges=counts.count(1),
                nonmanifold_edges=sum(c > 2 for c in counts),
                misoriented_edges=sum(1 for u in uses.values() if len(u) == 2 and u[0][1] == u[1][1]),
                nonmanifold_vertices=nonmanifold, zero_area_faces=sum(map(exact_zero_area, t)),
                faces_with_repeated_vertex=sum(len(set(face)) < 3 for face in ids),
                duplicate_faces=dups, shells=shells)


def exact_zero_area(face) -> bool:
    a, b, c = ([Fraction(float(x)) for x in p] for p in face)
    e1 = [b[k] - a[k] for k in range(3)]
    e2 = [c[k] - a[k] for k in range(3)]
    return all(e1[i] * e2[j] == e1[j] * e2[i] for i, j in ((0, 1), (1, 2), (2, 0)))


def counts(report) -> dict:
    return {k: getattr(report, k) for k in KEYS}


def soup(seed: int, n: int, points: int = 6) -> np.ndarray:
    rng = np.random.default_rng(seed)
    pts = rng.integers(0, 3, size=(points, 3)).astype(float)
    t = pts[rng.integers(0, points, size=(n, 3))]
    if seed % 3 == 0:                              # glue on closed pieces, flipped copies
        t = np.concatenate([t, cube_triangles(), cube_triangles()[:5, ::-1] + 1.0])
    return t


@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_counts_match_the_oracle_on_random_soups(seed, n):
    t = soup(seed, n)
    assert counts(topology(t)) == oracle(t)


@given(st.integers(0, 2**32 - 1), st.integers(1, 30))
def test_colliding_hashes_give_the_same_report(seed, n):
    # A hash that sees only x: corners at different points share hash groups, which the
    # exact confirmation must split (the vertex numbering may differ, the counts may not).
    t = soup(seed, n)
    expected = counts(topology(t))
    real = vertices._column_hashes
    try:
        vertices._column_hashes = lambda cols, scratch: real(
            np.stack([cols[:, 0], cols[:, 0] * 0, cols[:, 0] * 0], axis=1), scratch)
        assert counts(topology(t)) == expected
    finally:
        vertices._column_hashes = real


def test_confirmation_does_not_split_groups_of_a_clean_mesh(monkeypatch):
    def refuse(*args):
        raise AssertionError("no hash group should need splitting")
    monkeypatch.setattr(vertices, "_split_groups", refuse)
    t = np.concatenate([cube_triangles() + [3 * i, 0, 0] for i in range(3000)])  # 36k faces
    r = topology(t.astype(np.float32))
    assert r.closed and r.shells == 3000 and r.vertices == 24000


@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_unpacked_edge_keys_group_like_packed_ones(seed, n):
    t = soup(seed, n)
    a = group_edges(group_corners(_array_blocks(t), len(t)), packed=True)
    b = group_edges(group_corners(_array_blocks(t), len(t)), packed=False)
    for name in ("side", "forward", "starts", "counts", "boundary", "nonmanifold", "misoriented"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name


@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_fan_walk_agrees_with_the_union_find(seed, n):
    t = soup(seed, n)
    walked = topology(t).nonmanifold_vertices
    saved = fans.WALK
    try:
        fans.WALK = 0                              # every vertex through the union-find
        assert topology(t).nonmanifold_vertices == walked
    finally:
        fans.WALK = saved


def test_two_cones_touching_at_the_apex_are_one_non_manifold_vertex():
    # A clean vertex (every edge closed and oriented) with two fan cycles: the walk's case.
    ring = [(np.cos(a), np.sin(a)) for a in np.linspace(0, 2 * np.pi, 7)[:-1]]
    up = [[[0, 0, 0], [*ring[(i + 1) % 6], 1], [*ring[i], 1]] for i in range(6)]
    up += [[[0, 0, 1], [*ring[i], 1], [*ring[(i + 1) % 6], 1]] for i in range(6)]
    cone = np.array(up, dtype=float)
    down = cone * [1, 1, -1]
    r = topology(np.concatenate([cone, down[:, ::-1]]))
    assert r.closed and r.nonmanifold_vertices == 1 and r.shells == 2
    assert r.nonmanifold_vertex_samples[0].point == (0.0, 0.0, 0.0)
    assert counts(r) == oracle(np.concatenate([cone, down[:, ::-1]]))


def test_duplicate_pillow_is_found_by_the_closed_shortcut():
    # Every edge used twice: duplicates can only be two-face shells, as this pillow is.
    pillow = np.array([[[5, 5, 5], [6, 5, 5], [5, 6, 5]]], dtype=float)
    t = np.concatenate([cube_triangles(), pillow, pillow[:, ::-1]])
    r = topology(t)
    assert r.closed and r.duplicate_faces == 1 and r.duplicate_face_samples == ((12, 13),)


@given(st.integers(0, 2**32 - 1), st.integers(2, 60))
def test_duplicates_restricted_to_candidates_agree(seed, n):
    ids = np.random.default_rng(seed).integers(0, 4, size=(n, 3))
    everything = duplicate_faces(ids)
    assert np.array_equal(duplicate_faces(ids, np.arange(n)), everything)


@pytest.mark.parametrize("n", [1, 1000, 65536, 65537, 200_001])
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_streamed_volume_is_bit_identical_to_triangle_moments(n, dtype):
    rng = np.random.default_rng(n)
    t = (rng.normal(size=(n, 3, 3)) * 10 + 1e3).astype(dtype)
    expected = triangle_moments(t).volume
    got = SignedVolume(local_origin(t))
    for lo in range(0, n, 7777):                   # blocks that straddle the sum blocks
        got.add(t[lo:lo + 7777])
    assert got.volume() == expected


@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_duplicate_candidates_hold_every_duplicate(seed, n):
    from p3d_cli.mesh.faces import duplicate_candidates, repeated_vertex_faces

    t = soup(seed, n, points=5)
    t = np.concatenate([t, t[: n // 2, [1, 2, 0]]])        # plenty of duplicates
    corners = group_corners(_array_blocks(t), len(t))
    ids = corners.ids.reshape(-1, 3)
    edges = group_edges(corners)
    candidates = duplicate_candidates(len(t), edges.side, edges.starts, edges.counts,
                                      repeated_vertex_faces(ids))
    assert np.array_equal(duplicate_faces(ids, candidates), duplicate_faces(ids))
