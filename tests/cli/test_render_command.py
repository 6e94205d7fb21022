"""``p3d render``: files written as asked, one-line errors with documented exit codes."""

from __future__ import annotations

import json

import numpy as np
from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl

from p3d_cli.render.overlays import COLOURS
from p3d_cli.render.png import decode_png


def test_writes_a_png_of_the_size_asked(tmp_path):
    out = tmp_path / "box.png"
    result = run("render", "box:1,2,3", "-o", out, "--size", "320x200", "--json")
    assert result.exit_code == 0, result.output
    assert decode_png(out.read_bytes()).shape == (200, 320, 3)
    record = json.loads(result.output)
    assert record["width"] == 320 and record["height"] == 200 and record["format"] == "png"


def test_defects_of_a_mesh_file(tmp_path):
    mesh = tmp_path / "open.stl"
    write_binary_stl(mesh, cube_triangles()[2:])
    out = tmp_path / "open.png"
    result = run("render", mesh, "-o", out, "--show", "defects", "--view", "bottom")
    assert result.exit_code == 0, result.output
    pixels = decode_png(out.read_bytes())
    assert np.all(pixels == COLOURS["boundary"], axis=-1).sum() > 100


def test_svg_by_extension_or_flag(tmp_path):
    assert run("render", "sphere", "-o", tmp_path / "a.svg").exit_code == 0
    assert (tmp_path / "a.svg").read_text().startswith("<svg")
    assert run("render", "sphere", "-o", tmp_path / "b.png", "--svg").exit_code == 0
    assert (tmp_path / "b.png").read_text().startswith("<svg")


def test_errors_are_one_line_with_exit_status_2(tmp_path):
    cases = [
        (("render", "box"), "--output"),
        (("render", "box", "-o", tmp_path / "x.gif"), ".png or .svg"),
        (("render", "box", "-o", tmp_path / "x.png", "--show", "halo"), "halo"),
        (("render", "box", "-o", tmp_path / "x.png", "--size", "big"), "WIDTHxHEIGHT"),
        (("render", "box", "-o", tmp_path / "x.png", "--size", "20x20"), "--size"),
        (("render", "box", "-o", tmp_path / "x.png", "--show", "defects"), "not a mesh"),
        (("render", tmp_path / "missing.stl", "-o", tmp_path / "x.png"), "missing.stl"),
        (("render", "box", "-o", tmp_path / "no" / "x.png"), "does not exist"),
        (("render", "box", "-o", tmp_path / "x.png", "--elevation", "120"), "elevation"),
    ]
    for args, text in cases:
        result = run(*args)
        assert result.exit_code == 2, (args, result.output)
        lines = result.output.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("p3d: error: ") and text in lines[0], (args, lines)
    assert not (tmp_path / "x.png").exists()


def test_never_writes_over_its_input(tmp_path):
    mesh = tmp_path / "part.stl"
    write_binary_stl(mesh, cube_triangles())
    before = mesh.read_bytes()
    result = run("render", mesh, "-o", mesh, "--svg")
    assert result.exit_code != 0 and "input" in result.output
    assert mesh.read_bytes() == before


def test_help_has_an_example():
    result = run("render", "--help")
    assert result.exit_code == 0 and "p3d render part.stl -o part.png" in result.output
