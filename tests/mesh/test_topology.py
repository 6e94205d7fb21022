"""Topology checks: every count on meshes built with one defect each, and on the real meshes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.meshes import cube_triangles
from p3d_cli.errors import UnknownFormatError
from p3d_cli.mesh.closed import closed_exact
from p3d_cli.mesh.topology import SAMPLES, components, corner_vertex_ids, topology

CLEAN = dict(boundary_edges=0, nonmanifold_edges=0, misoriented_edges=0, nonmanifold_vertices=0,
             zero_area_faces=0, faces_with_repeated_vertex=0, degenerate_faces=0, duplicate_faces=0)


def counts(report) -> dict:
    return {k: getattr(report, k) for k in CLEAN}


def test_clean_cube():
    r = topology(cube_triangles())
    assert counts(r) == CLEAN
    assert (r.faces, r.vertices, r.edges, r.shells) == (12, 8, 18, 1)
    assert r.closed and r.oriented and r.manifold
    assert r.volume == 1.0
    assert [(s.faces, s.first_face, s.volume) for s in r.shell_list] == [(12, 0, 1.0)]


def test_inward_cube_is_closed_with_negative_volume():
    r = topology(cube_triangles()[:, ::-1])
    assert counts(r) == CLEAN and r.closed
    assert r.volume == -1.0


def test_missing_face_gives_three_boundary_edges_with_locations():
    r = topology(cube_triangles()[1:])
    assert counts(r) == {**CLEAN, "boundary_edges": 3}
    assert not r.closed and r.oriented and r.manifold
    assert len(r.boundary_edge_samples) == 3
    # The hole is the removed face (0,0,0) (1,1,0) (1,0,0): its sides are the boundary.
    hole = {frozenset(s.points) for s in r.boundary_edge_samples}
    assert hole == {frozenset({(0.0, 0.0, 0.0), (1.0, 1.0, 0.0)}),
                    frozenset({(1.0, 1.0, 0.0), (1.0, 0.0, 0.0)}),
                    frozenset({(1.0, 0.0, 0.0), (0.0, 0.0, 0.0)})}
    assert all(len(s.faces) == 1 for s in r.boundary_edge_samples)


def test_flipped_face_gives_three_misoriented_edges():
    t = cube_triangles()
    t[4] = t[4][::-1]
    r = topology(t)
    assert counts(r) == {**CLEAN, "misoriented_edges": 3}
    assert not r.closed and not r.oriented and r.manifold
    assert all(4 in s.faces and len(s.faces) == 2 for s in r.misoriented_edge_samples)


def test_duplicate_face_any_order_counts_once_and_makes_edges_nonmanifold():
    t = cube_triangles()
    extra = t[[0]][:, [1, 0, 2]]  # same vertices, opposite orientation
    r = topology(np.concatenate([t, extra]))
    assert r.duplicate_faces == 1
    assert r.duplicate_face_samples == ((0, 12),)
    assert r.nonmanifold_edges == 3 and r.boundary_edges == 0
    assert not r.closed and not r.manifold
    assert all(len(s.faces) == 3 for s in r.nonmanifold_edge_samples)


def test_degenerate_faces_repeated_vertex_and_collinear():
    t = cube_triangles()
    repeated = [[[0, 0, 0], [0, 0, 0], [1, 0, 0]]]  # uses a cube edge: it joins the shell
    collinear = [[[5, 5, 5], [6, 6, 6], [7, 7, 7]]]  # zero area, three distinct points
    point = [[[9, 9, 9], [9, 9, 9], [9, 9, 9]]]  # no edge at all
    r = topology(np.concatenate([t, repeated, collinear, point]).astype(float))
    assert r.faces_with_repeated_vertex == 2
    assert r.zero_area_faces == 3 and r.degenerate_faces == 3
    assert r.degenerate_face_samples == (12, 13, 14)
    # The repeated-vertex face's side (0,0,0)-(1,0,0) is used one way twice: 3 faces.
    assert r.nonmanifold_edges == 1
    # The collinear face has three boundary edges; the point face has none.
    assert r.boundary_edges == 3
    assert r.shells == 3  # cube (+ attached sliver), the collinear face, the point face


def test_tiny_but_nonzero_area_is_not_degenerate():
    t = np.array([[[0, 0, 0], [1, 0, 0], [0, 1e-300, 0]]])
    assert topology(t).zero_area_faces == 0


def test_two_cubes_touching_at_a_corner_two_shells_one_nonmanifold_vertex():
    t = cube_triangles()
    r = topology(np.concatenate([t, t + 1.0]))
    assert counts(r) == {**CLEAN, "nonmanifold_vertices": 1}
    assert r.closed and not r.manifold
    assert r.shells == 2 and [s.volume for s in r.shell_list] == [1.0, 1.0]
    assert r.nonmanifold_vertex_samples[0].point == (1.0, 1.0, 1.0)


def test_two_cubes_sharing_an_edge_make_it_nonmanifold():
    t = cube_triangles()
    r = topology(np.concatenate([t, t + [1.0, 1.0, 0.0]]))
    assert r.nonmanifold_edges == 1 and r.nonmanifold_vertices == 0
    assert r.shells == 1  # joined through the shared edge
    assert r.volume == 2.0


def test_cavity_is_a_negative_shell_and_samples_are_capped():
    outer = cube_triangles() * 4 - 1.5
    inner = cube_triangles()[:, ::-1]
    r = topology(np.concatenate([outer, inner]))
    assert r.closed and r.manifold and r.shells == 2
    assert [(s.faces, s.first_face, s.volume) for s in r.shell_list] == [(12, 0, 64.0), (12, 12, -1.0)]
    assert r.volume == 63.0
    soup = topology(cube_triangles()[:, None].repeat(1, 1).reshape(-1, 3, 3)[::2])
    assert soup.boundary_edges > SAMPLES and len(soup.boundary_edge_samples) == SAMPLES


def test_negative_zero_matches_zero():
    t = cube_triangles()
    t[t == 0.0] = -0.0
    t[0] = np.where(t[0] == 0.0, 0.0, t[0])
    assert topology(t).closed


def test_last_bit_difference_is_not_merged():
    t = cube_triangles()
    t[0, 0, 0] = np.nextafter(0.0, 1.0)
    r = topology(t)
    assert not r.closed and r.boundary_edges == 4


def test_empty_mesh():
    r = topology(np.zeros((0, 3, 3)))
    assert (r.faces, r.edges, r.shells, r.closed, r.volume) == (0, 0, 0, False, 0.0)


def test_vertex_ids_fall_back_to_exact_ids_on_hash_collision(monkeypatch):
    import p3d_cli.mesh.topology as topo
    monkeypatch.setattr(topo, "corner_hashes", lambda c: np.zeros(len(c), dtype=np.uint64))
    ids, points = corner_vertex_ids(cube_triangles())
    assert len(points) == 8
    assert np.array_equal(points[ids], cube_triangles())


@given(st.integers(0, 2**32 - 1), st.integers(1, 60))
def test_closed_agrees_with_closed_module_on_random_soups(seed, n):
    rng = np.random.default_rng(seed)
    # Few distinct points, so that edges are shared, duplicated, flipped and degenerate.
    pts = rng.integers(0, 4, size=(5, 3)).astype(float)
    t = pts[rng.integers(0, 5, size=(n, 3))]
    r = topology(t)
    if r.edges:  # closed_exact calls a soup of point-faces (no edge at all) closed; we do not
        assert r.closed == closed_exact(t)
    else:
        assert not r.closed
    assert r.degenerate_faces >= r.faces_with_repeated_vertex


@given(st.integers(0, 2**32 - 1))
def test_counts_are_invariant_under_face_order_and_rotation_of_corners(seed):
    rng = np.random.default_rng(seed)
    pts = rng.integers(0, 3, size=(6, 3)).astype(float)
    t = pts[rng.integers(0, 6, size=(30, 3))]
    shuffled = t[rng.permutation(len(t))][:, [1, 2, 0]]
    a, b = topology(t), topology(shuffled)
    assert counts(a) == counts(b) and a.shells == b.shells and a.edges == b.edges


@given(st.integers(0, 2**32 - 1), st.integers(1, 40), st.integers(0, 60))
def test_components_match_a_plain_search(seed, size, m):
    rng = np.random.default_rng(seed)
    a, b = rng.integers(0, size, m), rng.integers(0, size, m)
    got = components(size, a, b)
    neighbours = {i: set() for i in range(size)}
    for x, y in zip(a.tolist(), b.tolist()):
        neighbours[x].add(y)
        neighbours[y].add(x)
    label, count = [-1] * size, 0
    for start in range(size):
        if label[start] < 0:
            stack, label[start] = [start], count
            while stack:
                for y in neighbours[stack.pop()]:
                    if label[y] < 0:
                        label[y] = count
                        stack.append(y)
            count += 1
    assert got.count == count and got.labels.tolist() == label


def test_real_meshes_match_reference_topology(real_meshes, reference):
    from p3d_cli.io import load_mesh

    checked = []
    for name, entry in sorted(reference.items()):
        try:
            mesh = load_mesh(str(real_meshes / name))
        except UnknownFormatError:
            continue  # OBJ/PLY/OFF loaders may not be in yet: those files are checked when they are
        r = topology(mesh.triangles())
        expected = entry["topology"]
        got = {k: getattr(r, k) for k in expected}
        assert got == expected, name
        assert r.closed == entry["watertight"], name
        assert r.faces == entry["faces"], name
        if entry["watertight"]:  # an open surface's "volume" depends on the origin
            assert r.volume == pytest.approx(entry["volume"], rel=1e-9), name
        checked.append(name)
    assert any(n.lower().endswith(".stl") for n in checked), "no real STL mesh was checked"


@given(st.integers(0, 2**32 - 1), st.sampled_from(["holes", "flips", "doubled", "soup"]))
def test_open_volume_from_the_exact_edges_is_the_hashed_roads(seed, kind):
    """The volume of a mesh with unbalanced edges takes its boundary term from the exact edges
    ``topology`` found; it is the number the edge keys' road (``p3d props``') gives, bit for bit."""
    from p3d_cli.mesh.boundary import boundary_volume
    from p3d_cli.mesh.boundary_sides import unbalanced_of
    from p3d_cli.mesh.vertices import group_corners

    rng = np.random.default_rng(seed)
    t = np.concatenate([cube_triangles() + rng.integers(-3, 4, 3) for _ in range(3)])
    t = t * rng.choice([1.0, 0.1, 1e-3, 7.3])
    if kind == "holes":
        t = np.delete(t, rng.choice(len(t), 4, replace=False), axis=0)
    elif kind == "flips":
        t[rng.choice(len(t), 3, replace=False)] = t[rng.choice(len(t), 3, replace=False)][:, ::-1]
    elif kind == "doubled":
        t = np.concatenate([t, t[rng.choice(len(t), 5)][:, ::-1], t[rng.choice(len(t), 2)]])
    else:
        t = t + rng.normal(0, 1e-3, (len(t), 1, 3))
    blocks = lambda: iter([t])          # noqa: E731
    corners = group_corners(blocks, len(t))
    unbalanced = unbalanced_of(blocks)
    expected = corners.volume
    if unbalanced.ids.size:
        expected = corners.volume_sums.volume(boundary_volume(blocks(), unbalanced, corners.volume_sums.origin)[0])
    assert np.float64(topology(t).volume).view(np.uint64) == np.float64(expected).view(np.uint64)


@given(st.integers(0, 2**32 - 1))
def test_duplicates_of_a_mesh_with_holes_are_those_of_every_face(seed):
    """No edge used more than twice: the duplicates are found among the faces of shells of one
    or two faces; they are those a comparison of every face with every other finds."""
    from p3d_cli.mesh.faces import duplicate_faces

    rng = np.random.default_rng(seed)
    t = np.concatenate([cube_triangles() + rng.integers(-3, 4, 3) for _ in range(3)])
    t = np.delete(t, rng.choice(len(t), int(rng.integers(0, 5)), replace=False), axis=0)
    p, q, r = rng.integers(10, 20, (3, 3)).astype(float)
    planted = [[p, q, r], [q, r, p],               # a duplicate, the same way round
               [p + 9, r + 9, q + 9], [p + 9, q + 9, r + 9],   # a pillow
               [p + 30, p + 30, q + 30],           # one edge, used by its own two sides
               [r + 40, r + 40, r + 40], [r + 40, r + 40, r + 40]]   # point faces, twice
    t = np.concatenate([t, np.array(planted)[rng.permutation(len(planted))[:int(rng.integers(2, 8))]]])
    t = t[rng.permutation(len(t))]
    ids, _ = corner_vertex_ids(t)
    report = topology(t)
    expected = duplicate_faces(ids)
    assert report.duplicate_faces == len(expected)
    assert report.duplicate_face_samples == tuple((int(a), int(b)) for a, b in expected[:SAMPLES])
