"""The real meshes of ``../shared/real-meshes``: the open and inward ones come out passing
``p3d check``, or with the reason they do not; the clean ones are copied byte for byte."""

from __future__ import annotations

import pytest

import p3d_cli as p3d
from p3d_cli.repairs import repair_file

CLEAN = ("trimeshes__rockerarm.stl", "numpy-stl__rear_case.stl", "trimesh__1002_tray_bottom.STL",
         "trimesh__fuze.ply", "euclid__kitten.off", "common3d__spot_quadrangulated.obj")


def repaired(real_meshes, tmp_path, name, **options):
    out = tmp_path / ("out" + (".stl" if name.lower().endswith(".stl") else ".ply"))
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
def test_clean_real_meshes_are_copied_unchanged(real_meshes, tmp_path, name):
    report, out = repaired(real_meshes, tmp_path, name)
    assert report.ok and not report.changed and report.written in ("copied", "written")
    if report.written == "copied":
        assert out.read_bytes() == (real_meshes / name).read_bytes()


def test_the_inward_horse_is_turned_out_whole(real_meshes, tmp_path, reference):
    report, out = repaired(real_meshes, tmp_path, "common3d__horse.ply")
    assert report.fixed and report.ok and report.failed_before == ("outward",)
    assert report.step("outward").counts["faces_flipped"] == 96966
    assert report.step("orient").counts["faces_flipped"] == 0
    ref = reference["common3d__horse.ply"]
    assert report.after.volume == pytest.approx(-ref["volume"], rel=1e-12)
    assert report.mass.relative_volume_change == 0
    assert p3d.check(str(out)).ok
    same_counts(report, out)


def test_the_teapot_is_closed_but_keeps_its_pinched_vertex(real_meshes, tmp_path):
    report, out = repaired(real_meshes, tmp_path, "trimesh__teapot.stl")
    holes = report.step("holes")
    assert holes.counts["holes_filled"] == 6 and holes.counts["holes_left"] == 0
    assert report.after.boundary_edges == 0 and report.failed_after == ("manifold",)
    assert report.unfixed == ("manifold: 0 non-manifold edges and 1 non-manifold vertices remain; repair does not "
                              "cut or join surfaces (that would change the part's shape)",)
    assert not report.ok
    same_counts(report, out)


def test_the_bunny_loses_its_duplicates_and_says_why_it_stays_open(real_meshes, tmp_path):
    report, out = repaired(real_meshes, tmp_path, "trimesh__bunny.ply")
    assert report.step("duplicate").counts["faces_removed"] == 87
    assert report.failed_after == ("closed", "manifold")
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
