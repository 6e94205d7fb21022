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


def test_a_directory_search_takes_only_the_xml_files_that_are_meshes(tmp_path):
    """``.xml`` is DOLFIN XML's extension, and a robot package's manifest's, MJCF models' and
    launch files': the search reads each one's root element and takes the meshes only."""
    import meshio
    import numpy as np

    t = cube_triangles()
    points, inverse = np.unique(t.reshape(-1, 3), axis=0, return_inverse=True)
    meshio.write(tmp_path / "cube.xml", meshio.Mesh(points, [("triangle", inverse.reshape(-1, 3))]),
                 file_format="dolfin-xml")
    (tmp_path / "package.xml").write_text('<?xml version="1.0"?>\n<!-- a manifest -->\n<package format="3">'
                                          "<name>arm</name></package>\n")
    (tmp_path / "arm.xml").write_text('<mujoco model="arm"><worldbody/></mujoco>\n')
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "view.xml").write_text("<launch><node/></launch>\n")
    # COLLADA in a file named .xml is a mesh: its content says so.
    import trimesh

    (tmp_path / "sub" / "visual.xml").write_bytes(trimesh.creation.box().export(file_type="dae"))
    result = run("props", tmp_path, "--json")
    assert result.exit_code == 0, result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["source"] for r in records] == [str(tmp_path / "cube.xml"), str(tmp_path / "sub" / "visual.xml")]
    assert [r["volume"] for r in records] == [1.0, 1.0]
    assert "skipped files p3d does not read: 3 .xml" in result.stderr
    # Named, a manifest is refused in one line that says what it is.
    result = run("check", tmp_path / "package.xml")
    assert result.exit_code == 2
    assert result.stderr.strip() == (
        f"p3d: error: {tmp_path / 'package.xml'}: is an XML file whose root element is <package>, not a mesh (the "
        "XML meshes read are DOLFIN XML, COLLADA, AMF and VTK PolyData); pass the mesh files it names, or --format "
        "NAME for a mesh in another format")


def test_a_fifo_named_xml_in_a_directory_is_not_read_by_the_search(tmp_path):
    """The search reads a .xml file's first bytes to tell a mesh; a FIFO would block there. It
    is taken unread (and read at its turn like any FIFO, with the readers' time limit)."""
    import os
    import threading

    from p3d_cli.io import is_mesh_file

    os.mkfifo(tmp_path / "pipe.xml")
    answer = []
    search = threading.Thread(target=lambda: answer.append(is_mesh_file(str(tmp_path / "pipe.xml"))), daemon=True)
    search.start()
    search.join(timeout=5)
    if not answer:                       # blocked: a writer lets the search's read end
        with open(tmp_path / "pipe.xml", "wb"):
            pass
        search.join(timeout=5)
    assert answer == [True]


def test_a_named_xml_that_is_not_xml_says_so(tmp_path):
    (tmp_path / "junk.xml").write_bytes(b"\x00\x01 not xml at all")
    result = run("check", tmp_path / "junk.xml")
    assert result.exit_code == 2 and "junk.xml: is not XML, not a mesh (the XML meshes read are" in result.stderr
