"""Closed shells inside each other: exact winding numbers, nesting and the volume miscounted."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import p3d_cli as p3d
from helpers.solids import box, octahedron
from p3d_cli.mesh.rays import winding_number


def nesting(triangles):
    return p3d.check(np.asarray(triangles, dtype=float), require=["nesting"]).report.nesting


def blocks_of(triangles):
    return lambda: iter([np.asarray(triangles, dtype=float)])


@pytest.mark.parametrize("offset", [0.0, 1e8])
def test_winding_numbers_of_points_inside_outside_and_on_a_cube(offset):
    cube = box([0, 0, 0], [2, 2, 2]) + offset
    at = lambda *p: winding_number(np.array(p, dtype=float) + offset, blocks_of(cube))
    assert at(1, 1, 1) == 1 and at(3, 1, 1) == 0 and at(-1, 1, 1) == 0
    # Rays through edges and vertices of the cube's faces are counted once.
    assert at(1, 0.5, 0.5) == 1 and at(1, 1, 0.5) == 1 and at(-1, 0, 0) == 0 and at(-1, 1, 1) == 0
    assert at(0.5, 1, 1) == 1 and at(-1, 2, 2) == 0
    assert at(2, 1, 1) is None and at(1, 1, 2) is None and at(2, 2, 2) is None   # on the surface
    if offset == 0:                                     # a hair inside a face (rounds onto it at 1e8)
        assert at(1.5, 2 - 2 ** -40, 1) == 1 and at(1.5, 2 + 2 ** -40, 1) == 0
    assert winding_number(np.array([1, 1, 1.0]) + offset, blocks_of(cube[:, ::-1])) == -1


@given(st.tuples(*(st.integers(-4, 4) for _ in range(3))), st.sampled_from([1, 2]))
def test_winding_numbers_about_an_octahedron_match_exact_arithmetic(point, half):
    """Points of a grid (many on the faces' planes, edges and vertices' rays) against the
    octahedron |x| + |y| + |z| <= 2: inside, outside or on it, decided in fractions."""
    p = np.array(point, dtype=float) / half
    taxicab = sum(abs(Fraction(x)) for x in p)
    expected = None if taxicab == 2 else (1 if taxicab < 2 else 0)
    assert winding_number(p, blocks_of(octahedron([0, 0, 0], 2))) == expected


def test_a_hollow_part_is_a_valid_solid():
    result = nesting(np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2], inward=True)]))
    assert result.ok
    assert result.relations == ((1, 0, "inside"),)
    assert [(s.shell, s.inside, s.winding) for s in result.shells] == [(0, None, 1), (1, 0, 0)]
    assert result.counted_twice == 0 and result.counted_negative == 0


def test_an_island_in_a_cavity_is_valid_too():
    parts = [box([0, 0, 0], [5, 5, 5]), box([1, 1, 1], [4, 4, 4], inward=True), box([2, 2, 2], [3, 3, 3])]
    result = nesting(np.concatenate(parts))
    assert result.ok and {(s.shell, s.inside, s.winding) for s in result.shells} == {(0, None, 1), (1, 0, 0),
                                                                                       (2, 1, 1)}


def test_a_shell_inside_another_wound_alike_counts_its_volume_twice():
    result = nesting(np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2.5])]))
    assert not result.ok
    assert result.counted_twice == 1.5 and result.crossing_bound == 0
    assert [(s.shell, s.inside, s.winding) for s in result.shells] == [(0, None, 1), (1, 0, 2)]
    r = p3d.check(np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2.5])]))
    assert r.failed == ("nesting",)                  # no face crosses: no-self-intersection holds


def test_crossing_shells_bound_the_volume_counted_twice():
    result = nesting(np.concatenate([box([0, 0, 0], [2, 2, 2]), box([1, 1, 1], [3, 3, 4])]))
    assert not result.ok and result.relations == ((0, 1, "crossing"),)
    assert result.counted_twice == 0 and result.crossing_bound == 1.0   # exactly the common cube here


def test_a_cavity_in_no_body_counts_negative():
    result = nesting(np.concatenate([box([0, 0, 0], [2, 2, 2]), box([5, 5, 5], [6, 6, 6], inward=True)]))
    assert not result.ok and result.counted_negative == 1.0


def test_apart_and_touching_bodies_are_valid():
    for other in (box([3, 0, 0], [4, 1, 1]), box([2, 0, 0], [3, 1, 1]), box([2, 2, 2], [3, 3, 3])):
        result = nesting(np.concatenate([box([0, 0, 0], [2, 2, 2]), other]))
        assert result.ok and result.relations == ()


def test_a_body_touching_another_from_inside_everywhere_it_can():
    """A tetrahedron whose four vertices lie on four faces of a cube: every vertex is on the
    cube's surface, so its edges' midpoints decide: inside, wound alike, counted twice."""
    cube = box([0, 0, 0], [4, 4, 4])
    tet = np.array([[0, 2, 2], [4, 2, 1], [2, 0, 3], [2, 4, 3]], dtype=float)
    faces = [(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)]
    tet_triangles = tet[np.array(faces)]
    if p3d.props(tet_triangles).facts.closed and p3d.props(tet_triangles).properties.volume < 0:
        tet_triangles = tet_triangles[:, ::-1]
    result = nesting(np.concatenate([cube, tet_triangles]))
    assert result.relations == ((1, 0, "inside"),) and result.counted_twice > 0


def test_open_shells_take_no_part():
    cube = box([0, 0, 0], [3, 3, 3])
    result = nesting(np.concatenate([cube, box([1, 1, 1], [2, 2, 2])[1:]]))
    assert result.closed_shells == 1 and result.ok


def test_a_declared_unit_scales_the_crossings_points_and_the_nesting_volumes():
    # A scene file in millimetres is reported in metres (check's in_length_unit): the crossing
    # points by the factor, the volumes counted twice by its cube; the counts stay.
    report = p3d.check(np.concatenate([box([0, 0, 0], [2, 2, 2]), box([1, 1, 1], [3, 3, 4])])).report
    metres = report.in_length_unit(1e-3)
    found, scaled = report.self_intersections, metres.self_intersections
    assert scaled.count == found.count > 0
    for before, after in zip(found.samples, scaled.samples):
        assert after.faces == before.faces and after.point == tuple(x * 1e-3 for x in before.point)
    assert metres.nesting.crossing_bound == report.nesting.crossing_bound * 1e-9
    assert [s.volume for s in metres.nesting.shells] == [s.volume * 1e-9 for s in report.nesting.shells]
    assert metres.nesting.relations == report.nesting.relations


def big_cube_in_small_tetrahedron():
    """A cube of volume 729 whose first corner lies inside a tetrahedron of volume 1000/6 that
    crosses it, and whose box holds the cube's: the tetrahedron is the cube's only candidate
    outer shell, though the smaller."""
    tet = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], dtype=float)
    return np.concatenate([box([0.5, 0.5, 0.5], [9.5, 9.5, 9.5]), tet[np.array([(0, 2, 1), (0, 1, 3), (0, 3, 2),
                                                                                (1, 2, 3)])]])


def test_a_parent_smaller_than_its_child_is_wound_first():
    """Without the crossing pairs (p3d repair's question before it had them) the cube nests in
    the smaller tetrahedron: the windings follow the parents, not the volumes (it raised a
    KeyError), and the relation is the one found."""
    from p3d_cli.mesh.layout import Layout
    from p3d_cli.mesh.nesting import shell_nesting
    from p3d_cli.mesh.shells import Components

    t = big_cube_in_small_tetrahedron()
    points, inverse = np.unique(t.reshape(-1, 3), axis=0, return_inverse=True)
    faces = inverse.reshape(-1, 3)
    labels = np.repeat([0, 1], [12, 4])
    layout = Layout(faces.ravel(), len(points), Components(labels, 2), np.zeros(0, dtype=np.int64),
                    np.zeros((0, 2), dtype=np.int64), np.zeros(0, dtype=np.int64))
    found = shell_nesting(points, faces, layout, np.zeros((0, 2), dtype=np.int64))
    assert found.parent == {0: 1, 1: None}
    assert {(s.shell, s.inside, s.winding) for s in found.shells} == {(0, 1, 2), (1, None, 1)}
    # With the crossing pairs, as p3d check has them, neither is inside the other.
    result = nesting(t)
    assert result.relations == ((0, 1, "crossing"),) and all(s.inside is None for s in result.shells)


def test_parent_links_that_close_a_cycle_are_cut_at_the_largest_shell():
    from p3d_cli.mesh.nesting import _cut_cycles, _windings

    volume = np.array([5.0, 3.0, 4.0, 1.0, -2.0])
    parent = {0: 1, 1: 2, 2: 0, 3: 0, 4: 3}          # 0 -> 1 -> 2 -> 0, and 4 -> 3 -> 0
    _cut_cycles(parent, volume)
    assert parent == {0: None, 1: 2, 2: 0, 3: 0, 4: 3}
    assert _windings(parent, volume) == {0: 1, 2: 2, 1: 3, 3: 2, 4: 1}
    tie = {0: 1, 1: 0}
    _cut_cycles(tie, np.array([2.0, -2.0]))
    assert tie == {0: None, 1: 0}


def test_shells_boxed_together_are_those_whose_boxes_meet():
    from p3d_cli.mesh.nesting import boxed_together, shell_boxes

    t = np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2]), box([5, 0, 0], [6, 1, 1]),
                        box([3, 0, 0], [4, 1, 1])])          # nested pair, one apart, one touching the first
    points, inverse = np.unique(t.reshape(-1, 3), axis=0, return_inverse=True)
    faces = inverse.reshape(-1, 3)
    labels = np.repeat([0, 1, 2, 3], 12)
    lo, hi = shell_boxes(points, faces, labels, 4)
    np.testing.assert_array_equal(lo, [[0, 0, 0], [1, 1, 1], [5, 0, 0], [3, 0, 0]])
    np.testing.assert_array_equal(hi, [[3, 3, 3], [2, 2, 2], [6, 1, 1], [4, 1, 1]])
    assert boxed_together(lo, hi, np.array([0, 1, 2, 3])).tolist() == [0, 1, 3]
    assert boxed_together(lo, hi, np.array([1, 2])).tolist() == []
    assert boxed_together(lo, hi, np.array([2])).tolist() == []
