"""``repair_file``: what is written where, and that the output re-read gives the reported numbers."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

import p3d_cli as p3d
from helpers.meshes import write_binary_stl
from p3d_cli.errors import OutputError
from p3d_cli.repairs import repair_file
from p3d_cli.io.writers import write_mesh


@pytest.mark.parametrize("ext", [".stl", ".ply", ".obj", ".off"])
def test_outputs_read_back_by_p3d_and_trimesh_give_the_reported_numbers(tmp_path, cube, ext):
    source = tmp_path / "open.stl"
    write_binary_stl(source, cube[2:])                      # float32 corners, one side missing
    out = tmp_path / f"fixed{ext}"
    report = repair_file(source, out)
    assert report.fixed and report.written == "written" and report.output == str(out)
    again = p3d.props(str(out))
    after = report.mass.after
    assert again.properties.volume == pytest.approx(after.volume, rel=1e-15, abs=0)
    assert np.allclose(again.properties.center_of_mass, after.center_of_mass, rtol=1e-15, atol=1e-15)
    assert np.allclose(again.properties.inertia, after.inertia, rtol=1e-14, atol=1e-15)
    if ext in (".stl", ".ply"):                             # float32 kept: the very same sums
        assert again.properties.volume == after.volume
    assert p3d.check(str(out)).ok
    theirs = trimesh.load(str(out), process=False, force="mesh")
    theirs.merge_vertices(merge_tex=True, merge_norm=True)   # STL stores corners, not vertices
    assert theirs.is_watertight and theirs.volume == pytest.approx(after.volume, rel=1e-12)
    assert np.allclose(theirs.center_mass, after.center_of_mass, rtol=1e-12, atol=1e-12)


def test_untouched_stl_records_keep_their_corners_bit_for_bit(tmp_path, cube):
    source = tmp_path / "in.stl"
    broken = (cube * 0.001 + 123.456).astype(np.float32)
    write_binary_stl(source, np.concatenate([broken[:3], broken[5:]]))      # faces 3, 4 gone
    out = tmp_path / "out.stl"
    report = repair_file(source, out)
    assert report.fixed
    record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    given = np.frombuffer(source.read_bytes()[84:], record)["corners"]
    written = np.frombuffer(out.read_bytes()[84:], record)["corners"]
    assert written[:10].tobytes() == given.tobytes()
    assert report.step("holes").new_faces == (10, 11)


def test_a_mesh_check_passes_is_copied_byte_for_byte_or_not_at_all(tmp_path, cube):
    source = tmp_path / "good.stl"
    write_binary_stl(source, cube, header=b"exported by some CAD program, kept as it is")
    out = tmp_path / "copy.stl"
    report = repair_file(source, out)
    assert report.ok and not report.changed and report.written == "copied"
    assert out.read_bytes() == source.read_bytes()
    skipped = tmp_path / "skipped.stl"
    report = repair_file(source, skipped, only_if_needed=True)
    assert report.ok and report.written == "not written" and not skipped.exists()
    converted = tmp_path / "good.obj"
    report = repair_file(source, converted)          # another format: converted, not repaired
    assert report.written == "written" and p3d.check(str(converted)).ok
    assert len(p3d.load_mesh(str(converted)).triangles()) == 12


def test_the_input_is_never_overwritten_unless_in_place(tmp_path, cube):
    source = tmp_path / "part.obj"
    write_mesh(source, cube.reshape(-1, 3), np.arange(36).reshape(12, 3)[2:])
    before = source.read_bytes()
    with pytest.raises(OutputError, match="would overwrite the input"):
        repair_file(source, source)
    assert source.read_bytes() == before
    report = repair_file(source, in_place=True)
    assert report.fixed and report.written == "written" and report.output == str(source)
    assert p3d.check(str(source)).ok
    assert not list(tmp_path.glob(".*p3d-tmp"))          # no temporary file left behind
    report = repair_file(source, in_place=True)          # now clean: left alone
    assert report.written == "unchanged"


def test_a_volume_change_over_the_limit_writes_nothing(tmp_path, cube):
    source = tmp_path / "open.stl"
    write_binary_stl(source, np.delete(cube, [2, 3], axis=0))      # the z = 1 side missing
    out = tmp_path / "out.stl"
    report = repair_file(source, out, max_volume_change=1e-6)
    assert report.fixed and not report.within_limit and not report.ok
    assert report.written == "refused" and not out.exists()
    # The open input's volume by props' convention (tetrahedra from the origin) is 2/3.
    assert report.mass.before.volume == pytest.approx(2 / 3) and report.mass.relative_volume_change == pytest.approx(0.5)
    report = repair_file(source, out, max_volume_change=0.6)
    assert report.ok and out.exists()


def test_inward_repair_changes_no_volume(tmp_path, cube):
    source = tmp_path / "inward.stl"
    write_binary_stl(source, cube[:, [0, 2, 1]])
    report = repair_file(source, tmp_path / "out.stl", max_volume_change=0.0)
    assert report.ok and report.mass.volume_change == 0 and report.mass.center_shift == 0


def test_a_dry_run_writes_nothing(tmp_path, cube):
    source = tmp_path / "open.stl"
    write_binary_stl(source, cube[2:])
    report = repair_file(source)
    assert report.fixed and report.written == "dry run" and report.output is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["open.stl"]


def test_what_a_file_holds_beyond_positions_and_faces_is_never_dropped_in_place(tmp_path, cube):
    source = tmp_path / "textured.obj"
    lines = ["mtllib part.mtl", "usemtl steel"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in cube.reshape(-1, 3).tolist()]
    lines += ["vt 0 0", "vn 0 0 1"] + [f"f {3 * i + 1}/1/1 {3 * i + 2}/1/1 {3 * i + 3}/1/1" for i in range(2, 12)]
    source.write_text("\n".join(lines) + "\n")
    before = source.read_bytes()
    with pytest.raises(OutputError, match="would drop its material libraries, materials, normals, "
                                          "texture coordinates"):
        repair_file(source, in_place=True)
    assert source.read_bytes() == before
    report = repair_file(source, tmp_path / "fixed.obj")
    assert report.fixed and report.notes[-1].startswith("not carried into the output: the input's material")
    coloured = tmp_path / "coloured.stl"
    write_binary_stl(coloured, cube[2:])
    data = bytearray(coloured.read_bytes())
    data[84 + 48:84 + 50] = b"\x1f\x80"                    # a colour in face 0's attribute word
    coloured.write_bytes(bytes(data))
    with pytest.raises(OutputError, match="attribute words"):
        repair_file(coloured, in_place=True)


def test_an_ascii_stl_repaired_in_place_stays_ascii_and_keeps_its_decimals(tmp_path, cube):
    from helpers.meshes import write_ascii_stl

    source = tmp_path / "part.stl"
    part = cube * 0.1 + 0.3                                 # decimals no float32 holds
    write_ascii_stl(source, part[2:])
    report = repair_file(source, in_place=True)
    assert report.fixed and report.written == "written"
    assert source.read_bytes().startswith(b"solid")
    again = p3d.load_mesh(str(source))
    assert again.format == "stl-ascii"
    assert np.array_equal(again.triangles()[:10], part[2:])
    assert p3d.check(str(source)).ok
