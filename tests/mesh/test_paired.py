"""The fast path of ``p3d check`` (meshes whose sides pair up) against the general path.

Every report of the fast path (``p3d_cli.mesh.paired``) must equal, field for field and bit
for bit, the report the general path (one sort of corner keys, ``p3d_cli.mesh.vertices``)
gives for the same triangles: closed meshes in any face order, corner rotation, dtype and
place, with planted defects that keep every side paired (solids touching at a point, two-face
pillows, collinear pillows, many shells), and with weak hashes that make edge keys collide.
Meshes with a defect that breaks the pairing must leave the fast path.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.kernels import needs_kernels, numpy_road
from helpers.meshes import cube_triangles
from helpers.topology import fast_path_refused, real_surface_meshes
import p3d_cli.mesh.paired as paired
import p3d_cli.mesh.topology as topo
from p3d_cli.mesh.topology import _array_blocks, topology
from test_topology_oracle import counts, oracle


def torus(u: int, v: int, shift=(0.0, 0.0, 0.0)) -> np.ndarray:
    """A closed grid torus of ``2 u v`` triangles, wound outward."""
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = 3.0 + np.cos(phi)
    points = np.stack([ring * np.cos(theta), ring * np.sin(theta), np.sin(phi)], -1).reshape(-1, 3)
    a, b = (i * v + j).ravel(), (((i + 1) % u) * v + j).ravel()
    c, d = (((i + 1) % u) * v + (j + 1) % v).ravel(), (i * v + (j + 1) % v).ravel()
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return points[faces] + np.asarray(shift)


def general(t: np.ndarray):
    """The general path's report (the fast path refused)."""
    with fast_path_refused():
        return topology(t)


def fast(t: np.ndarray, hasher=None):
    """The fast path's report, or None when it refuses."""
    t = np.asarray(t)
    found = paired.paired_topology(_array_blocks(t), len(t), hasher=hasher)
    return None if found is None else topo._paired_report(_array_blocks(t), len(t), found)


def same(a, b) -> None:
    assert dataclasses.asdict(a) == dataclasses.asdict(b)


def clean_mesh(seed: int) -> np.ndarray:
    """A clean mesh with defects that keep every side paired, shuffled and placed at random."""
    rng = np.random.default_rng(seed)
    parts = [torus(int(rng.integers(3, 9)), int(rng.integers(3, 9)))]
    kind = seed % 5
    if kind == 1:       # cubes touching the torus at points: non-manifold vertices
        points = np.unique(parts[0].reshape(-1, 3), axis=0)
        for k in rng.choice(len(points), 2, replace=False):     # two distinct points
            parts.append(cube_triangles() * 0.01 + points[k])   # small: touching nothing else
    elif kind == 2:     # a pillow (a face and its reverse): a two-face shell, a duplicate
        pillow = np.array([[[9, 9, 9], [10, 9, 9], [9, 10, 9]]], dtype=float)
        parts += [pillow, pillow[:, [0, 2, 1]]]
    elif kind == 3:     # a collinear pillow: two zero-area faces, a duplicate
        flat = np.array([[[9, 9, 9], [10, 10, 10], [12, 12, 12]]], dtype=float)
        parts += [flat, flat[:, [1, 0, 2]]]
    elif kind == 4:     # many separate cubes, and two touching along nothing but a corner
        parts += [cube_triangles() + [20 + 2 * k, 0, 0] for k in range(int(rng.integers(1, 6)))]
        parts.append(cube_triangles() + [19, -1, -1])
    t = np.concatenate(parts)
    t = t[rng.permutation(len(t))]
    roll = rng.integers(0, 3, len(t))
    t = np.stack([np.roll(face, int(r), axis=0) for face, r in zip(t, roll)])
    t = t * float(rng.choice([1.0, 0.5, 3.0])) + rng.normal(size=3) * float(rng.choice([0.0, 1.0, 1e4]))
    return t.astype(np.float32 if seed % 2 else np.float64)


@given(st.integers(0, 2**32 - 1))
def test_fast_path_report_equals_the_general_one(seed):
    t = clean_mesh(seed)
    got = fast(t)
    assert got is not None
    expected = general(t)
    same(got, expected)
    assert counts(got) == oracle(t)


@given(st.integers(0, 2**32 - 1))
def test_defects_that_break_the_pairing_leave_the_fast_path(seed):
    rng = np.random.default_rng(seed)
    t = clean_mesh(seed & ~1)                       # a float64 clean mesh
    f = int(rng.integers(0, len(t)))
    kind = seed % 4
    if kind == 0:
        t = np.delete(t, f, axis=0)                 # a hole
    elif kind == 1:
        t[f] = t[f, ::-1]                           # a flipped face
    elif kind == 2:
        t = np.concatenate([t, t[f:f + 1]])         # a duplicate: edges used three times
    else:
        t[f, 1] = t[f, 0]                           # a repeated vertex
    assert fast(t) is None
    same(topology(t), general(t))


def torus_hasher(u: int, v: int, classes: int, period: float = 20.0):
    """A corner hash of points of ``torus(u, v)`` shifted by multiples of ``period`` in x: the
    point's grid index modulo ``classes``, the same in every copy. Edge keys of the copies
    collide in bulk (and, for ``classes`` below ``u v``, of unrelated edges of one copy);
    the two ends of a side never do (no two neighbours' indices differ by ``classes``)."""
    grid = {}
    for face in torus(u, v):
        for p in face:
            grid.setdefault(tuple(p.tolist()), len(grid))
    points = np.array(list(grid))

    def hasher(cols: np.ndarray) -> np.ndarray:
        out = np.empty((3, cols.shape[2]), dtype=np.uint64)
        for slot in range(3):
            for k in range(cols.shape[2]):
                p = cols[slot, :, k].copy()
                p[0] -= period * round(p[0] / period)       # back to the first copy
                nearest = int(np.argmin(((points - p) ** 2).sum(axis=1)))
                out[slot, k] = np.uint64((nearest % classes) * 0x9E3779B97F4A7C15 % 2**64)
        return out
    return hasher


@pytest.mark.parametrize("classes", [101, 1000])
def test_colliding_edge_keys_are_paired_exactly(classes, monkeypatch):
    t = np.concatenate([torus(12, 9), torus(12, 9, shift=(20.0, 0.0, 0.0))])
    t = t[np.random.default_rng(classes).permutation(len(t))]
    calls = []
    real = paired.exact_twins
    monkeypatch.setattr(paired, "exact_twins", lambda *a: calls.append(a[1].size) or real(*a))
    got = fast(t, torus_hasher(12, 9, classes))
    assert calls and calls[0] >= 4, "the weak hash should have made edge keys collide"
    assert got is not None
    same(got, general(t))


def test_falsely_paired_sides_fail_the_exact_confirmation(monkeypatch):
    # Two tori with the same weak hashes, the second wound inward, each with the same face
    # removed: the two holes' sides pair up by key, though they are far apart. The exact
    # confirmation must refuse, and the general path then reports the two holes.
    a = torus(8, 6)
    b = (a + [30.0, 0.0, 0.0])[:, ::-1]
    t = np.concatenate([a[1:], b[1:]])
    hasher = torus_hasher(8, 6, 1000, period=30.0)

    refused = []
    real = paired._confirm
    monkeypatch.setattr(paired, "_confirm", lambda *a: (lambda r: refused.append(r is None) or r)(real(*a)))
    assert fast(t, hasher) is None
    assert refused == [True]
    r = general(t)
    assert r.boundary_edges == 6 and r.shells == 2


@given(st.integers(0, 2**32 - 1), st.integers(1, 300), st.sampled_from([np.int32, np.int64]),
       st.sampled_from(["kernel", "numpy"]))
def test_fan_ids_number_the_cycles_of_a_permutation(seed, size, dtype, road):
    # Both roads (the compiled cycle walk and numpy's pointer doubling) against a walk here.
    rng = np.random.default_rng(seed)
    pi = rng.permutation(size).astype(dtype)
    if seed % 2:                                    # long cycles, as around a busy vertex
        order = rng.permutation(size)
        pi = np.empty(size, dtype=dtype)
        pi[order] = np.roll(order, 1)
    if road == "numpy" or paired.compiled() is None:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(paired, "compiled", lambda: None)
            check_fan_ids(pi)
    else:
        check_fan_ids(pi)


def check_fan_ids(pi: np.ndarray) -> None:
    size = pi.size
    expected = np.full(size, -1)
    count = 0
    for c in range(size):                           # cycles in order of their first member
        if expected[c] < 0:
            x = c
            while expected[x] < 0:
                expected[x] = count
                x = int(pi[x])
            count += 1
    fan, got_count, first = paired._fan_ids(pi.copy())
    assert got_count == count and np.array_equal(fan, expected) and fan.dtype == pi.dtype
    assert first.dtype == bool
    assert np.array_equal(np.flatnonzero(first), [np.flatnonzero(expected == k)[0] for k in range(count)])


@needs_kernels
@pytest.mark.parametrize("pi", [[1, 1, 0], [0, 3], [2, 0, 0], [-1, 0], [-1]])
def test_the_compiled_cycle_walk_refuses_what_is_not_a_permutation(pi):
    with pytest.raises(ValueError, match="permutation"):
        paired.compiled().fan_cycles(np.array(pi, dtype=np.int32), np.zeros(len(pi), dtype=bool))


def test_a_shared_top_hash_of_distinct_points_is_not_a_vertex(monkeypatch):
    # Hashes of the fans' points that agree (all of them, here) are only
    # candidates: distinct points stay distinct vertices.
    t = torus(5, 4)
    monkeypatch.setattr(paired, "corner_hashes", lambda points: np.full(len(points), 7 << 40, dtype=np.uint64))
    got = fast(t)
    assert got is not None and got.vertices == 20 and got.nonmanifold_vertices == 0


def test_real_meshes_fast_and_general_agree(real_meshes):
    taken = 0
    for mesh in real_surface_meshes(real_meshes):
        found = paired.paired_topology(mesh.read_blocks, mesh.face_count)
        with fast_path_refused():
            expected = topo.topology_of_blocks(mesh.read_blocks, mesh.face_count)
        if found is None:
            assert not (expected.closed and expected.faces_with_repeated_vertex == 0)
            continue
        taken += 1
        same(topo._paired_report(mesh.read_blocks, mesh.face_count, found), expected)
    assert taken >= 3


@given(st.integers(0, 2**32 - 1))
def test_general_path_fan_walk_and_union_find_agree_on_clean_meshes(seed):
    # Clean meshes now take the fast path; the general path's two fan methods are still
    # compared on them here (tests/mesh/test_topology_oracle.py does so on random soups).
    import p3d_cli.mesh.fans as fans

    t = clean_mesh(seed)
    walked = general(t)
    saved = fans.WALK
    try:
        fans.WALK = 0
        same(general(t), walked)
    finally:
        fans.WALK = saved


def test_general_path_does_not_split_hash_groups_of_a_clean_mesh(monkeypatch):
    import p3d_cli.mesh.vertices as vertices

    def refuse(*args):
        raise AssertionError("no hash group should need splitting")
    monkeypatch.setattr(vertices, "_split_groups", refuse)
    t = np.concatenate([cube_triangles() + [3 * i, 0, 0] for i in range(3000)]).astype(np.float32)
    r = general(t)
    assert r.closed and r.shells == 3000 and r.vertices == 24000
    same(fast(t), r)


def test_high_valence_fans_need_more_doubling_rounds_and_agree():
    # Cones of 300 segments: 300 corners around each apex (many doubling rounds); apex to apex,
    # a non-manifold vertex whose two fans are both long.
    k = 300
    angle = np.linspace(0, 2 * np.pi, k, endpoint=False)
    ring = np.stack([np.cos(angle), np.sin(angle), np.zeros(k)], 1)
    apex, base = np.array([0.0, 0.0, 1.0]), np.zeros(3)
    cone = np.array([[apex, ring[i], ring[(i + 1) % k]] for i in range(k)]
                    + [[base, ring[(i + 1) % k], ring[i]] for i in range(k)])
    cone = cone[np.random.default_rng(0).permutation(len(cone))]
    two = np.concatenate([cone, (cone * [1, 1, -1])[:, ::-1] + [0, 0, 2]])
    for t in (cone, two):
        got = fast(t)
        assert got is not None
        same(got, general(t))
    assert got.nonmanifold_vertices == 1 and got.shells == 2
    assert got.nonmanifold_vertex_samples[0].point == (0.0, 0.0, 1.0)


@needs_kernels
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_large_meshes_take_the_compiled_pass_and_agree(dtype):
    # Past 2**16 sides the keys are bucketed and every block after the first is read in place
    # (volume, zero-area filter, keys): collinear pillows (zero-area faces, duplicates) and
    # cubes touching the torus at a point, spread over the blocks, as the numpy code finds them.
    rng = np.random.default_rng(5)
    t = torus(150, 80, shift=(0.25, -1.0, 0.5))
    flat = np.array([[[9, 9, 9], [10, 10, 10], [12, 12, 12]]], dtype=float)
    corner = t[7, 0]
    parts = [t] + [np.concatenate([flat + 10 * k, flat[:, [1, 0, 2]] + 10 * k]) for k in range(5)]
    parts.append(cube_triangles() * 0.01 + corner)
    t = np.concatenate(parts)
    t = t[rng.permutation(len(t))].astype(dtype)
    got = fast(t)
    assert got is not None and got.zero_area_faces == 10 and got.nonmanifold_vertices == 1
    same(got, numpy_road(fast, t))
    same(got, general(t))


@needs_kernels
def test_a_nan_in_a_later_block_is_named_as_the_numpy_code_names_it():
    from p3d_cli.errors import InputError

    t = torus(150, 80)
    t[20000, 1, 2] = np.nan
    messages = []
    for road in (lambda f, *a: f(*a), numpy_road):
        with pytest.raises(InputError) as caught:
            road(paired.paired_topology, _array_blocks(t), len(t), "mesh.stl")
        messages.append(str(caught.value))
    assert messages[0] == messages[1] and "face 20000" in messages[0]
