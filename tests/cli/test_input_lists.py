"""Inputs: NUL-separated lists (-0), and files a directory search skips, counted and named."""

from __future__ import annotations

import json


from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl


def test_nul_separated_list_keeps_spaces_and_newlines(tmp_path):
    names = [tmp_path / "a b.stl", tmp_path / "c\nd.stl", tmp_path / " lead.stl"]
    for i, path in enumerate(names):
        write_binary_stl(path, cube_triangles() * (i + 1))
    listing = tmp_path / "list"
    listing.write_bytes(b"".join(bytes(p) + b"\0" for p in names))
    for source, stdin in ((listing, None), ("-", listing.read_bytes())):
        result = run("props", "--files-from", source, "-0", "--json", input=stdin)
        assert result.exit_code == 0, result.stderr
        records = [json.loads(line) for line in result.stdout.splitlines()]
        assert [r["source"] for r in records] == [str(p) for p in names]
        assert [r["volume"] for r in records] == [1.0, 8.0, 27.0]


def test_null_without_a_list_is_a_usage_error():
    result = run("props", "box", "--null")
    assert result.exit_code == 2 and "-0/--null: given without --files-from" in result.stderr


def test_skipped_files_are_counted_by_extension(tmp_path):
    # Extensions no reader of p3d's (nor meshio's) takes (.3mf and .glb, used here before, are read now).
    for name in ("a.fbx", "b.fbx", "c.3ds", "README"):
        (tmp_path / name).write_bytes(b"x")
    write_binary_stl(tmp_path / "part.stl", cube_triangles())
    summary = tmp_path / "summary.json"
    result = run("props", tmp_path, "--summary", f"json:{summary}")
    assert result.exit_code == 0
    assert "skipped files p3d does not read: 2 .fbx, 1 .3ds, 1 without extension" in result.stderr
    counts = json.loads(summary.read_text())
    assert counts["skipped_by_extension"] == {"": 1, ".fbx": 2, ".3ds": 1} and counts["skipped"] == 4
    assert (counts["inputs"], counts["ok"]) == (1, 1)


def test_directory_of_only_unread_files_says_what_it_holds(tmp_path):
    for name in ("a.fbx", "b.blend", "c.3ds"):
        (tmp_path / name).write_bytes(b"x")
    result = run("check", tmp_path)
    assert result.exit_code == 2
    assert "directory holds no mesh files, only files p3d does not read (1 .3ds, 1 .blend, 1 .fbx)" in result.stderr


def test_a_list_line_with_a_nul_byte_is_that_input_s_error_not_a_bug(tmp_path):
    """Issue 27: a --files-from line holding a NUL byte was an internal error (exit 3)."""
    from click.testing import CliRunner

    from helpers.meshes import cube_triangles, write_binary_stl
    from p3d_cli.cli.main import cli

    write_binary_stl(tmp_path / "a.stl", cube_triangles())
    listing = tmp_path / "list.txt"
    listing.write_bytes(f"{tmp_path / 'a.stl'}\nbad\0name.stl\n".encode())
    for command in ("check", "props", "bounds"):
        result = CliRunner().invoke(cli, [command, "--files-from", str(listing)])
        assert result.exit_code == 2, (command, result.output)
        errors = [line for line in result.stderr.splitlines() if line.startswith("p3d: error:")]
        assert errors == ["p3d: error: bad\\x00name.stl: the name holds a NUL byte, which no file name can; "
                          "a NUL-separated list (find -print0, git ls-files -z) needs -0"]
        assert "internal error" not in result.output and "\0" not in result.output
