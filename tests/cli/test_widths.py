"""Human output fits 80 columns: every line of every command's table on the sample meshes,
shape specs and example scenes (run from the repository, as the README's examples are)."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from p3d_cli.cli.main import cli

REPO = Path(__file__).resolve().parents[2]
SAMPLES = sorted(str(p.relative_to(REPO)) for p in (REPO / "sample_meshes").iterdir()
                 if p.suffix in (".stl", ".obj", ".off", ".ply"))
SCENES = sorted(str(p.relative_to(REPO)) for p in (REPO / "examples").glob("*.yaml"))

COMMANDS = [
    ["props", *SAMPLES],
    ["props", *SAMPLES, "--about", "1,2,3", "--density", "7850"],
    ["props", "box:1,2,3", "--rotate", "z:30", "--translate", "-1000,2000,-3000", "--about", "-1,-2,-3"],
    ["props", "sphere:2", "--method", "montecarlo", "--samples", "2000"],
    ["bounds", *SAMPLES, "cylinder:1,1,2", "--rotate", "x:33"],
    ["check", *SAMPLES],
    *[["solve", scene] for scene in SCENES],
    *[["solve", scene, "--steps", "3", "--dt", "0.01"] for scene in SCENES],
]


@pytest.mark.parametrize("args", COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_every_line_fits_80_columns(args, monkeypatch):
    monkeypatch.chdir(REPO)
    result = CliRunner().invoke(cli, args)
    assert result.exit_code == 0, result.output
    wide = [line for line in result.stdout.splitlines() if len(line) > 80]
    assert result.stdout and not wide, "\n".join(wide)


def test_check_locations_wrap_within_80_columns(tmp_path, monkeypatch):
    import numpy as np

    from helpers.meshes import cube_triangles, write_binary_stl

    monkeypatch.chdir(tmp_path)
    write_binary_stl(tmp_path / "open.stl", cube_triangles()[4:] * [1234.5678, 2.2, 3.3] + [1e5, -2e4, np.pi])
    result = CliRunner().invoke(cli, ["check", "open.stl"])
    assert result.exit_code == 1
    lines = result.stdout.splitlines()
    assert all(len(line) <= 80 for line in lines), lines
    assert lines[1] == "  8 boundary edges (e.g." and lines[2].startswith("    face ")
    import json

    samples = json.loads(CliRunner().invoke(cli, ["check", "open.stl", "--json"]).stdout)["samples"]["boundary_edges"]
    assert lines[-1].endswith(")") and sum(line.count("face ") for line in lines[2:]) == len(samples) > 1


def test_no_singular_plural_slips(monkeypatch, tmp_path):
    from helpers.meshes import cube_triangles, write_binary_stl

    write_binary_stl(tmp_path / "one.stl", cube_triangles()[:1])
    for command in ("props", "bounds", "check"):
        out = CliRunner().invoke(cli, [command, str(tmp_path / "one.stl")]).stdout
        assert "1 face," in out or "1 face)" in out, out
        assert "1 faces" not in out
