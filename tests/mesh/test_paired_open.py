"""The fast path of ``p3d check`` on meshes with boundary edges, against the general path.

``paired_topology(..., boundary=True)`` also takes a soup whose every edge is used once each
way or once (a boundary edge): its report (``topology._open_report``) and layout must equal,
field for field and bit for bit, those of the general path (which groups the corners and the
edges) on the same triangles: tori with holes in any face order and dtype, holes touching at a
vertex (a non-manifold vertex), one face, strips, open shells beside closed ones, duplicate and
zero-area faces, weak hashes that make edge keys collide, and the open real meshes. Meshes with
any other problem edge must leave the fast path; so must a falsely paired side.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers.kernels import needs_kernels, numpy_road
from helpers.meshes import cube_triangles
from helpers.topology import fast_path_refused, real_surface_meshes
import p3d_cli.mesh.paired as paired
import p3d_cli.mesh.topology as topo
from p3d_cli.mesh.topology import _array_blocks
from test_paired import torus, torus_hasher
from test_topology_oracle import counts, oracle


def general(t: np.ndarray):
    """The general path's report and layout (the fast path refused)."""
    with fast_path_refused():
        return topo.topology_and_layout(_array_blocks(t), len(t))


def fast(t: np.ndarray, hasher=None):
    """The fast path's report and layout with boundary edges, or None when it refuses."""
    t = np.asarray(t)
    found = paired.paired_topology(_array_blocks(t), len(t), hasher=hasher, boundary=True)
    if found is None:
        return None
    assert found.boundary.size, "a closed mesh: test_paired's business"
    return topo._open_report(_array_blocks(t), len(t), found)


def same(got, expected) -> None:
    """Reports equal field for field; layouts equal where their readers look (the vertex ids
    as a partition of the corners: the fast path numbers vertices otherwise)."""
    (report, layout), (want, want_layout) = got, expected
    assert dataclasses.asdict(report) == dataclasses.asdict(want)
    assert layout.shells.count == want_layout.shells.count
    np.testing.assert_array_equal(layout.shells.labels, want_layout.shells.labels)
    np.testing.assert_array_equal(layout.open_shells, want_layout.open_shells)
    np.testing.assert_array_equal(layout.zero_area, want_layout.zero_area)
    assert layout.crowded_edges.shape == (0, 2) and want_layout.crowded_edges.shape == (0, 2)
    pairs = np.unique(np.stack([layout.ids, want_layout.ids], axis=1), axis=0)
    assert len(pairs) == len(np.unique(layout.ids)) == len(np.unique(want_layout.ids))
    assert layout.edges is None and layout.ids.max() < layout.vertex_count


def holed(seed: int) -> np.ndarray:
    """A torus with a few faces removed at random, shuffled and its corners rotated."""
    rng = np.random.default_rng(seed)
    t = torus(int(rng.integers(4, 12)), int(rng.integers(4, 12)))
    t = np.delete(t, rng.choice(len(t), int(rng.integers(1, 6)), replace=False), axis=0)
    t = t[rng.permutation(len(t))]
    return np.roll(t, int(rng.integers(0, 3)), axis=1)


@given(st.integers(0, 2**32 - 1), st.sampled_from([np.float32, np.float64]))
@settings(max_examples=40)
def test_holed_tori_fast_and_general_agree(seed, dtype):
    t = holed(seed).astype(dtype)
    got = fast(t)
    assert got is not None
    same(got, general(t))
    assert counts(got[0]) == oracle(t)


def test_two_holes_touching_at_a_vertex_make_a_nonmanifold_vertex():
    # Quad (i, j) of the grid is faces (a b c), (a c d) with c at (i+1, j+1); face (a' b' c')
    # of quad (i+1, j+1) starts there. Without both faces, two holes meet at that one vertex,
    # whose faces form two open fans.
    u, v = 8, 6
    t = torus(u, v)
    first, second = 2 * v + 3, 3 * v + 4          # (a b c) of quads (2, 3) and (3, 4)
    assert (t[first, 2] == t[second, 0]).all()
    t = np.delete(t, [first, second], axis=0)
    got = fast(t)
    assert got is not None
    report = got[0]
    assert report.boundary_edges == 6 and report.nonmanifold_vertices == 1
    assert report.nonmanifold_vertex_samples[0].point == tuple(float(x) for x in torus(u, v)[first, 2])
    same(got, general(t))
    assert counts(report) == oracle(t)


@pytest.mark.parametrize("name", ["one face", "two faces", "strip", "fan", "collinear face"])
def test_small_open_meshes_fast_and_general_agree(name):
    one = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=float)
    if name == "one face":
        t = one
    elif name == "two faces":
        t = np.concatenate([one, np.array([[[1, 0, 0], [1, 1, 0], [0, 1, 0]]], dtype=float)])
    elif name == "strip":                           # a long strip, every face on the boundary
        x = np.arange(40, dtype=float)
        low, high = np.stack([x, 0 * x, 0 * x], 1), np.stack([x, 0 * x + 1, x * x / 100], 1)
        t = np.concatenate([np.stack([low[:-1], low[1:], high[:-1]], 1),
                            np.stack([low[1:], high[1:], high[:-1]], 1)])
    elif name == "fan":                             # an open fan round one vertex
        ring = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 3, 7)])
        t = np.stack([np.zeros((6, 3)), ring[:-1], ring[1:]], 1)
    else:                                           # three distinct collinear points
        t = np.array([[[0, 0, 0], [1, 1, 1], [3, 3, 3]]], dtype=float)
    got = fast(t)
    assert got is not None
    same(got, general(t))
    assert counts(got[0]) == oracle(t)


def test_open_and_closed_shells_duplicates_and_zero_area_faces():
    rng = np.random.default_rng(5)
    holes = np.delete(torus(9, 7), [4, 30, 31], axis=0)
    pillow = np.array([[[9, 9, 9], [10, 9, 9], [9, 10, 9]]], dtype=float)      # a duplicate
    flat = np.array([[[19, 9, 9], [20, 10, 10], [22, 12, 12]]], dtype=float)   # zero area
    lone = np.array([[[0, 0, 30], [1, 0, 30], [0, 1, 30]]], dtype=float)       # an open shell
    t = np.concatenate([cube_triangles() + 40.0, holes, pillow, pillow[:, ::-1], flat, flat[:, [1, 0, 2]],
                        lone, cube_triangles()[2:] - 40.0])
    t = t[rng.permutation(len(t))]
    got = fast(t)
    assert got is not None
    report, layout = got
    assert report.duplicate_faces == 2 and report.zero_area_faces == 2 and report.shells == 6
    assert layout.open_shells.size == 3
    same(got, general(t))
    assert counts(report) == oracle(t)


@pytest.mark.parametrize("classes", [101, 1000])
def test_colliding_edge_keys_of_an_open_mesh_are_sorted_out_exactly(classes, monkeypatch):
    t = np.concatenate([np.delete(torus(12, 9), [0, 50], axis=0),
                        np.delete(torus(12, 9, shift=(20.0, 0.0, 0.0)), [7], axis=0)])
    t = t[np.random.default_rng(classes).permutation(len(t))]
    calls = []
    real = paired.exact_edges
    monkeypatch.setattr(paired, "exact_edges", lambda *a: calls.append(a[1].size) or real(*a))
    got = fast(t, torus_hasher(12, 9, classes))
    assert calls, "the weak hash should have made edge keys collide"
    assert got is not None and got[0].boundary_edges == 9
    same(got, general(t))
    same(numpy_road(fast, t, torus_hasher(12, 9, classes)), got)


def test_falsely_paired_boundary_sides_fail_the_exact_confirmation():
    # Two tori with the same weak hashes, the second wound inward, each with the same face
    # removed: the holes' sides pair up by key, though they are far apart.
    a = torus(8, 6)
    b = (a + [30.0, 0.0, 0.0])[:, ::-1]
    t = np.concatenate([a[1:], b[1:]])
    assert fast(t, torus_hasher(8, 6, 1000, period=30.0)) is None
    assert fast(t) is not None


@pytest.mark.parametrize("defect", ["non-manifold edge", "misoriented edge", "repeated vertex"])
def test_other_problem_edges_leave_the_fast_path(defect):
    t = np.delete(torus(8, 6), [3], axis=0)
    if defect == "non-manifold edge":     # a third face on an edge
        extra = t[10].copy()
        extra[2] = [9.0, 9.0, 9.0]
        t = np.concatenate([t, extra[None]])
    elif defect == "misoriented edge":    # one face flipped
        t[20] = t[20, ::-1]
    else:
        t = np.concatenate([t, np.array([[[0, 0, 0], [0, 0, 0], [1, 0, 0]]], dtype=float)])
    assert fast(t) is None
    report = topo.topology(t)
    assert dataclasses.asdict(report) == dataclasses.asdict(general(t)[0])


@needs_kernels
@given(st.integers(0, 2**32 - 1))
@settings(max_examples=20)
def test_kernels_and_numpy_agree_on_open_meshes(seed):
    t = holed(seed)
    got = fast(t)
    same(got, numpy_road(fast, t))


@needs_kernels
@given(st.integers(0, 2**32 - 1), st.integers(1, 300), st.sampled_from([np.int32, np.int64]))
def test_fan_chains_number_chains_and_cycles_as_the_union_find(seed, size, dtype):
    # A random one-to-one map with open ends: a permutation whose arrows are cut at random.
    rng = np.random.default_rng(seed)
    pi = rng.permutation(size).astype(dtype)
    pi[rng.random(size) < 0.3] = -1
    ids, count, first = paired._chain_ids(pi.copy())
    want_ids, want_count, want_first = numpy_road(paired._chain_ids, pi.copy())
    assert count == want_count
    np.testing.assert_array_equal(ids, want_ids)
    np.testing.assert_array_equal(first, want_first)
    # Independent: each fan's smallest corner is first, and c and pi[c] share a fan.
    linked = np.flatnonzero(pi >= 0)
    assert (ids[linked] == ids[pi[linked]]).all()
    assert first.sum() == count and (np.unique(ids, return_index=True)[1] == np.flatnonzero(first)).all()


def test_real_open_meshes_fast_and_general_agree(real_meshes):
    taken = 0
    for mesh in real_surface_meshes(real_meshes):
        found = paired.paired_topology(mesh.read_blocks, mesh.face_count, boundary=True)
        if found is None or found.boundary.size == 0:
            continue
        taken += 1
        got = topo._open_report(mesh.read_blocks, mesh.face_count, found)
        with fast_path_refused():
            expected = topo.topology_and_layout(mesh.read_blocks, mesh.face_count)
        same(got, expected)
    assert taken >= 1
