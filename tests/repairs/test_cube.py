"""``p3d.repair`` on the cube with each defect of the issue: what it fixes, what it leaves, and
that the faces it does not touch keep their coordinates bit for bit."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import p3d_cli as p3d
from p3d_cli.errors import UsageError
from p3d_cli.repairs import repair


def exact_volume(triangles: np.ndarray) -> Fraction:
    """The signed volume of a closed mesh in rational arithmetic (signed tetrahedra from 0)."""
    total = Fraction(0)
    for a, b, c in triangles.tolist():
        a, b, c = ([Fraction(x) for x in p] for p in (a, b, c))
        total += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                  + a[2] * (b[0] * c[1] - b[1] * c[0]))
    return total / 6


def untouched_rows_equal(out: np.ndarray, triangles: np.ndarray, rows) -> None:
    """The output's first rows are the input's ``rows``, bit for bit."""
    expected = triangles[list(rows)]
    assert out[:len(expected)].tobytes() == expected.tobytes()


def test_a_cube_without_a_side_is_filled_to_volume_exactly_one(cube):
    mesh, report = repair(cube[2:])                     # both triangles of the z = 0 side gone
    assert report.failed_before == ("closed",)
    assert report.fixed and report.changed and not report.unfixed
    holes = report.step("holes")
    assert holes.counts == {"holes_filled": 1, "holes_left": 0, "faces_added": 2, "boundary_edges_not_in_loops": 0}
    assert holes.new_faces == (10, 11)
    assert holes.places[0]["flatness"] == 0.0 and holes.places[0]["edges"] == 4
    assert exact_volume(mesh.triangles) == 1
    assert report.mass.after.volume == 1.0
    untouched_rows_equal(mesh.triangles, cube, range(2, 12))
    assert p3d.check(mesh.source).ok


def test_a_cube_without_one_triangle_gets_it_back(cube):
    mesh, report = repair(cube[1:])
    assert report.fixed and report.step("holes").counts["faces_added"] == 1
    assert sorted(map(sorted, mesh.triangles[-1].tolist())) == sorted(map(sorted, cube[0].tolist()))
    assert exact_volume(mesh.triangles) == 1


def test_flipped_faces_are_flipped_back_and_only_they(cube):
    broken = cube.copy()
    broken[[4, 5]] = broken[[4, 5]][:, [0, 2, 1]]       # one side wound the wrong way
    mesh, report = repair(broken)
    orient = report.step("orient")
    assert orient.counts == {"faces_flipped": 2, "shells": 1} and orient.faces == (4, 5)
    assert report.step("outward").counts["shells_flipped"] == 0
    assert report.fixed and exact_volume(mesh.triangles) == 1
    assert mesh.triangles.tobytes() == cube.tobytes()   # the very faces of the cube, corner for corner


def test_an_inward_cube_is_flipped_whole(cube):
    mesh, report = repair(cube[:, [0, 2, 1]])
    assert report.failed_before == ("outward",)
    assert report.step("orient").counts["faces_flipped"] == 0
    outward = report.step("outward")
    assert outward.counts["shells_flipped"] == 1 and outward.faces == tuple(range(12))
    assert report.fixed and exact_volume(mesh.triangles) == 1
    assert mesh.triangles.tobytes() == cube.tobytes()
    assert report.mass.relative_volume_change == 0      # props measures the enclosed solid both times


def test_a_majority_wound_inward_is_oriented_then_turned_out(cube):
    broken = cube[:, [0, 2, 1]].copy()
    broken[0] = cube[0]                                  # one face "right", eleven inward
    mesh, report = repair(broken)
    assert report.step("orient").faces == (0,)           # the one face against its shell
    assert report.step("outward").counts["faces_flipped"] == 12
    assert report.fixed and mesh.triangles.tobytes() == cube.tobytes()


def test_duplicate_and_degenerate_faces_are_removed(cube):
    sliver = [[[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.0, 0.0]]]   # collinear: zero area
    point = [[[1.0, 1.0, 1.0]] * 3]                                    # three equal corners
    broken = np.concatenate([cube[:6], cube[[2]], sliver, cube[6:], cube[[7]][:, ::-1], point])
    mesh, report = repair(broken)
    assert set(report.failed_before) >= {"no-duplicate", "no-degenerate"}
    assert report.step("degenerate").faces == (7, 15)
    assert report.step("duplicate").faces == (6, 14)
    assert report.step("duplicate").places == ({"face": 6, "repeats": 2}, {"face": 14, "repeats": 9})
    assert report.fixed and exact_volume(mesh.triangles) == 1
    assert mesh.triangles.tobytes() == cube.tobytes()


def test_a_vertex_split_by_1e9_is_welded_only_when_asked(cube):
    broken = cube.copy()
    broken[0, 0] += [1e-9, 0, 0]                         # one corner of vertex 0 off by 1e-9
    _, report = repair(broken)
    assert not report.fixed and report.step("weld").ran is False
    assert report.after.boundary_edges == 4              # left open: nothing merged by default
    # The gap is a slit of width 1e-9 along two edges: a loop that folds onto itself.
    assert report.step("holes").places[0]["reason"] == "seen along its normal the loop crosses itself"
    mesh, report = repair(broken, weld=1e-6)
    weld = report.step("weld")
    assert weld.counts["vertices_merged"] == 1 and weld.counts["largest_distance"] == pytest.approx(1e-9)
    assert weld.faces == (0,) and report.fixed
    assert exact_volume(mesh.triangles) == 1
    untouched_rows_equal(mesh.triangles[1:], cube[1:], range(11))


def test_the_weld_step_merges_only_points_of_the_mesh(cube):
    # Two cubes touching at one corner: a non-manifold vertex, whose two fans the topology's
    # fast path numbers apart (one id left unused). The weld must find nothing to merge, not
    # an unused row of the vertex table.
    pair = np.concatenate([cube, cube - 1])
    _, report = repair(pair, weld=1e-9)
    assert report.failed_before == ("manifold",) and not report.fixed
    weld = report.step("weld")
    assert weld.counts["vertices_merged"] == 0 and weld.counts["largest_distance"] == 0.0
    assert weld.places == () and report.after.faces == 24


def test_a_hollow_part_stays_hollow(cube):
    inner = (cube[:, [0, 2, 1]] - 0.5) * 0.5 + 0.5       # a cavity, wound inward
    hollow = np.concatenate([cube, inner])
    mesh, report = repair(hollow)
    assert report.fixed and not report.changed           # it passes check: left as it is
    assert mesh.triangles.tobytes() == hollow.tobytes()
    mesh, report = repair(np.concatenate([cube[2:], inner]))   # the outer shell opened
    assert report.fixed and report.step("outward").counts == {
        "shells_flipped": 0, "faces_flipped": 0, "closed_shells": 2, "cavities": 1}
    assert exact_volume(mesh.triangles) == Fraction(7, 8)


def test_a_hollow_part_wound_inward_is_turned_with_its_cavity(cube):
    inner = (cube[:, [0, 2, 1]] - 0.5) * 0.5 + 0.5
    mesh, report = repair(np.concatenate([cube, inner])[:, [0, 2, 1]])
    assert report.step("outward").counts["shells_flipped"] == 2
    assert report.fixed and exact_volume(mesh.triangles) == Fraction(7, 8)


def test_crossing_shells_are_not_nested_and_stay_as_they_are(cube):
    """A cube with seven corners inside a tetrahedron and one outside: the shells cross, so
    neither is inside the other and neither is turned as a cavity (repair turned the cube
    inward, nested by the winding number of one corner)."""
    tet = np.array([[0, 0, 0], [10, 0, 0], [0, 10, 0], [0, 0, 10]], dtype=np.float64)
    t = np.concatenate([cube * 4 + 0.5, tet[np.array([(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])]])
    mesh, report = repair(t)
    assert report.failed_before == ("no-self-intersection", "nesting")
    assert report.step("outward").counts == {"shells_flipped": 0, "faces_flipped": 0, "closed_shells": 2,
                                             "cavities": 0}
    assert report.failed_after == report.failed_before and not report.changed
    assert mesh.triangles.tobytes() == t.tobytes()


def test_closed_with_no_boundary_left_says_which_edges_keep_it_open(cube):
    # A tetrahedron on one edge of the cube, outside it: that edge has four faces
    # (non-manifold), no edge has one.
    corners = np.array([[0, 0, 0], [1, 0, 0], [0.5, -1, -1], [0.5, -1, -0.2]], dtype=np.float64)
    tet = corners[np.array([(0, 1, 2), (0, 3, 1), (0, 2, 3), (1, 3, 2)])]
    if exact_volume(tet) < 0:
        tet = tet[:, [0, 2, 1]]
    _, report = repair(np.concatenate([cube, tet]))
    closed = [u for u in report.unfixed if u.startswith("closed:")]
    assert report.after.boundary_edges == 0 and report.after.nonmanifold_edges > 0
    assert closed == [f"closed: no boundary edge remains, but {report.after.nonmanifold_edges} non-manifold edges "
                      "do (see manifold)"]


def test_a_non_planar_hole_is_reported_and_left(cube):
    broken = np.delete(cube, [0, 4], axis=0)             # a triangle of z = 0 and one of y = 0: a bent loop
    mesh, report = repair(broken)
    holes = report.step("holes")
    assert holes.counts["holes_filled"] == 0 and holes.counts["holes_left"] == 1
    assert "not flat" in holes.places[0]["reason"] and holes.places[0]["flatness"] > 0.1
    assert not report.fixed and report.unfixed[0].startswith("closed: 4 boundary edges remain")
    assert not report.changed and mesh.triangles.tobytes() == broken.tobytes()
    mesh, report = repair(broken, fill_holes="any")
    assert report.fixed and exact_volume(mesh.triangles) == 1


def test_float32_stays_float32_bit_for_bit(cube):
    far = (cube * 0.1 + 1000.0).astype(np.float32)        # float32 coordinates far from the origin
    mesh, report = repair(far[2:])
    assert mesh.triangles.dtype == np.float32 and mesh.coordinate_dtype == "float32"
    assert report.fixed
    untouched_rows_equal(mesh.triangles, far, range(2, 12))
    assert mesh.vertices.dtype == np.float32


def test_steps_left_out_are_not_run_and_say_so(cube):
    mesh, report = repair(cube[2:], steps="-holes")
    assert not report.step("holes").ran and not report.fixed
    assert report.unfixed == ("closed: 4 boundary edges remain (the holes step was not asked for)",)
    assert mesh.triangles.tobytes() == cube[2:].tobytes()


def test_a_sliver_in_the_surface_is_removed_and_its_t_junction_closed(cube):
    """A cap sliver (0, 1, m), m the midpoint of edge 0-1, between the bottom face and the side
    face split at m: removing it leaves a hole of no area, closed by splitting the bottom face
    at m. Nothing moves; the volume stays exactly 1."""
    v0, v1, v5 = cube[4][0], cube[4][1], cube[4][2]              # face 4 is (0, 1, 5): y = 0
    m = (v0 + v1) / 2
    side = np.array([[v0, m, v5], [m, v1, v5]])
    sliver = np.array([[v0, v1, m]])
    broken = np.concatenate([cube[:4], side, cube[5:], sliver])
    mesh, report = repair(broken)
    assert report.failed_before == ("no-degenerate",)
    assert report.step("degenerate").faces == (13,)
    holes = report.step("holes")
    assert holes.counts["faces_split"] == 1 and holes.faces == (0,) and holes.new_faces == (13,)
    assert holes.places[0]["split_face"] == 0
    assert report.fixed and exact_volume(mesh.triangles) == 1
    untouched_rows_equal(mesh.triangles[1:], broken[1:13], range(12))


def test_a_mesh_of_nothing_but_degenerate_faces_is_left_whole():
    flat = np.array([[[0, 0, 0], [1, 0, 0], [2, 0, 0]], [[0, 0, 0], [0, 0, 0], [1, 1, 1]]], dtype=float)
    mesh, report = repair(flat)
    assert not report.fixed and not report.changed and len(mesh.triangles) == 2
    assert "removing them would leave nothing" in report.step("degenerate").notes[0]


def test_a_filling_that_would_cross_another_face_is_left(cube):
    """An open-topped box with a spike standing through the opening's plane: the filling of the
    top would cross the spike, so the hole is left, and said."""
    open_box = np.delete(cube, [2, 3], axis=0)                    # the z = 1 side missing
    spike = np.array([[0.4, 0.4, 0.5], [0.6, 0.4, 0.5], [0.5, 0.6, 0.5], [0.5, 0.5, 1.5]])
    tetra = spike[[[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]]
    mesh, report = repair(np.concatenate([open_box, tetra]))
    holes = report.step("holes")
    assert holes.counts["holes_filled"] == 0
    assert holes.places[0]["reason"] == "its filling would cross other faces"
    assert not report.changed and not report.fixed


def test_require_picks_the_checks_that_decide(cube):
    crossing = np.concatenate([cube, cube + 0.5])                  # two boxes through each other
    _, report = repair(crossing)
    assert report.failed_before == ("no-self-intersection", "nesting") and not report.fixed
    assert report.unfixed[0].startswith("no-self-intersection: ")
    _, report = repair(crossing, require=["closed", "oriented", "outward", "manifold"])
    assert report.fixed and report.after.self_intersections is None
    with pytest.raises(UsageError, match="no check named 'watertight'"):
        repair(cube, require=["watertight"])


def test_parts_side_by_side_need_no_crossing_test(cube, monkeypatch):
    # Two closed parts apart, one wound inward: turned out, and the nesting asks no
    # self-intersection test (no two boxes meet); nested ones do.
    import p3d_cli.mesh.intersections as intersections

    calls = []
    real = intersections.self_intersections
    monkeypatch.setattr(intersections, "self_intersections", lambda *a, **k: calls.append(len(a[1])) or real(*a, **k))
    from p3d_cli.repairs import solidity

    points = np.unique(np.concatenate([cube, cube + 5]).reshape(-1, 3), axis=0)
    index = {tuple(p): i for i, p in enumerate(points.tolist())}
    faces = np.array([[index[tuple(p)] for p in tri] for tri in np.concatenate([cube, cube + 5]).tolist()])
    labels = np.repeat([0, 1], 12)
    assert solidity.nesting_depths(points, faces, labels, 2, np.array([0, 1])) == {0: 0, 1: 0}
    assert calls == []
    inner = (cube - 0.5) * 0.5 + 0.5
    points = np.unique(np.concatenate([cube, inner]).reshape(-1, 3), axis=0)
    index = {tuple(p): i for i, p in enumerate(points.tolist())}
    faces = np.array([[index[tuple(p)] for p in tri] for tri in np.concatenate([cube, inner]).tolist()])
    assert solidity.nesting_depths(points, faces, labels, 2, np.array([0, 1])) == {0: 0, 1: 1}
    assert calls == [24]
