"""The real meshes of ``../shared/real-meshes``: the open and inward ones come out passing
``p3d check``, or with the reason they do not; the clean ones are copied byte for byte."""

from __future__ import annotations

import pytest

import p3d_cli as p3d
from p3d_cli.repairs import repair_file

CLEAN = ("trimeshes__rockerarm.stl", "numpy-stl__rear_case.stl", "trimesh__1002_tray_bottom.STL",
         "trimesh__fuze.ply", "euclid__kitten.off", "common3d__spot_quadrangulated.obj")


def repaired(real_meshes, tmp_path, name, **options):
    out = tmp_path / ("out" + (real_meshes / name).suffix.lower())
    report = repair_file(real_meshes / name, out, **options)
    return report, out


def same_counts(report, out):
    """The report's "after" is what p3d check says of the file written."""
    again = p3d.check(str(out)).report
    assert (again.faces, again.boundary_edges, again.nonmanifold_edges, again.nonmanifold_vertices,
            again.misoriented_edges, again.duplicate_faces, again.degenerate_faces) == (
        report.after.faces, report.after.boundary_edges, report.after.nonmanifold_edges,
        report.after.nonmanifold_vertices, report.after.misoriented_edges, report.after.duplicate_faces,
        report.after.degenerate_faces)
    assert again.volume == report.after.volume


@pytest.mark.parametrize("name", CLEAN)
def test_closed_real_meshes_are_copied_unchanged(real_meshes, tmp_path, name):
    """Closed and outward: nothing repair can change. Some cross themselves (check's
    no-self-intersection): said, and left, as repair moves no face."""
    report, out = repaired(real_meshes, tmp_path, name)
    assert not report.changed and report.written == "copied"
    assert out.read_bytes() == (real_meshes / name).read_bytes()
    assert set(report.failed_after) <= {"no-self-intersection"}
    assert report.ok == (report.failed_after == ())
    if not report.ok:
        assert report.unfixed[0].startswith("no-self-intersection: ")


def test_the_inward_horse_is_turned_out_whole(real_meshes, tmp_path, reference):
    """Turned out whole; the four face pairs it crosses itself at (p3d check finds them) are
    left, and said."""
    report, out = repaired(real_meshes, tmp_path, "common3d__horse.ply")
    assert report.failed_before == ("outward",) and report.failed_after == ("no-self-intersection",)
    assert report.after.self_intersections.count == 4 and not report.ok
    assert report.unfixed[0].startswith("no-self-intersection: 4 face pairs cross or overlap")
    assert report.step("outward").counts["faces_flipped"] == 96966
    assert report.step("orient").counts["faces_flipped"] == 0
    ref = reference["common3d__horse.ply"]
    assert report.after.volume == pytest.approx(-ref["volume"], rel=1e-12)
    assert report.mass.relative_volume_change == 0
    assert p3d.check(str(out)).failed == ("no-self-intersection",)
    same_counts(report, out)


def test_the_teapot_gets_the_holes_that_cross_nothing_filled(real_meshes, tmp_path):
    """Six holes; the filling of the one where the spout meets the body would cross the body's
    faces, and is left. The teapot crosses itself already (spout and handle through the body,
    46 face pairs) and keeps its pinched vertex: said, and left."""
    report, out = repaired(real_meshes, tmp_path, "trimesh__teapot.stl")
    holes = report.step("holes")
    assert holes.counts["holes_filled"] == 5 and holes.counts["holes_left"] == 1
    left = [place for place in holes.places if not place["filled"]]
    assert left[0]["reason"] == "its filling would cross other faces" and left[0]["edges"] == 8
    assert report.failed_after == ("closed", "manifold", "no-self-intersection", "nesting")
    assert report.unfixed[1] == ("manifold: 0 non-manifold edges and 1 non-manifold vertices remain; repair does "
                                 "not cut or join surfaces (that would change the part's shape)")
    # No filled face crosses anything: every crossing pair is the input's own.
    crossing = report.after.self_intersections.pairs
    assert (crossing < 894).all()
    assert not report.ok
    same_counts(report, out)


def test_the_bunny_loses_its_duplicates_and_says_why_it_stays_open(real_meshes, tmp_path):
    report, out = repaired(real_meshes, tmp_path, "trimesh__bunny.ply")
    assert report.step("duplicate").counts["faces_removed"] == 87
    assert report.failed_after == ("closed", "manifold", "no-self-intersection")
    assert any(line.startswith("manifold: 125 non-manifold edges") for line in report.unfixed)
    holes = report.step("holes")
    assert holes.counts["holes_left"] == 3 and all("not flat" in p["reason"] for p in holes.places)
    same_counts(report, out)
    report, out = repaired(real_meshes, tmp_path, "trimesh__bunny.ply", fill_holes="any")
    assert report.step("holes").counts["holes_filled"] == 3
    same_counts(report, out)


def test_the_soup_is_lone_triangles_and_is_left(real_meshes, tmp_path):
    report, out = repaired(real_meshes, tmp_path, "trimesh__soup.stl")
    holes = report.step("holes")
    assert holes.counts == {"holes_filled": 0, "holes_left": 100, "faces_added": 0, "boundary_edges_not_in_loops": 0}
    assert all("outline of a lone triangle" in p["reason"] for p in holes.places)
    assert not report.changed and report.written == "copied"
    assert out.read_bytes() == (real_meshes / "trimesh__soup.stl").read_bytes()
