"""``p3d check`` on the command line: every count, the verdicts and the exit statuses."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
from click.testing import CliRunner

from helpers.cli import run
from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl
from p3d_cli.cli.main import cli

REQUIRED_KEYS = {"source", "ok", "closed", "boundary_edges", "nonmanifold_edges", "misoriented_edges",
                 "degenerate_faces", "duplicate_faces", "shells", "volume"}
COUNT_KEYS = ("boundary_edges", "nonmanifold_edges", "misoriented_edges", "nonmanifold_vertices",
              "degenerate_faces", "zero_area_faces", "faces_with_repeated_vertex", "duplicate_faces")
ZERO = dict.fromkeys(COUNT_KEYS, 0)


def flipped(t, i):
    t = t.copy()
    t[i] = t[i][::-1]
    return t


CUBE = cube_triangles()
TOUCHING = np.concatenate([CUBE, CUBE + 1.0])
DEGENERATE = np.concatenate([CUBE, [[[2, 2, 2], [2, 2, 2], [3, 2, 2]]], [[[4, 0, 0], [5, 0, 0], [6, 0, 0]]]])

#: name -> (triangles, expected counts, failed checks, shells)
DEFECTS = {
    "clean": (CUBE, {}, [], 1),
    "open": (CUBE[1:], {"boundary_edges": 3}, ["closed"], 1),
    "misoriented": (flipped(CUBE, 4), {"misoriented_edges": 3}, ["closed", "oriented"], 1),
    "inward": (CUBE[:, ::-1], {}, ["outward"], 1),
    "duplicate": (np.concatenate([CUBE, CUBE[:1]]),
                  {"duplicate_faces": 1, "nonmanifold_edges": 3}, ["closed", "manifold", "no-duplicate"], 1),
    "degenerate": (DEGENERATE,
                   {"degenerate_faces": 2, "zero_area_faces": 2, "faces_with_repeated_vertex": 1,
                    "boundary_edges": 3},  # the sliver's one edge is used both ways
                   ["closed", "no-degenerate"], 3),
    "touching": (TOUCHING, {"nonmanifold_vertices": 1}, ["manifold"], 2),
    "shared-edge": (np.concatenate([CUBE, CUBE + [1.0, 1.0, 0.0]]), {"nonmanifold_edges": 1},
                    ["closed", "manifold"], 1),
}


@pytest.mark.parametrize("name", DEFECTS)
def test_each_defect_counts_verdict_and_exit_status(tmp_path, name):
    triangles, counts, failed, shells = DEFECTS[name]
    path = tmp_path / f"{name}.stl"
    write_binary_stl(path, triangles)
    result = run("check", path, "--json")
    assert result.exit_code == (1 if failed else 0), result.stderr
    record = json.loads(result.stdout)
    assert REQUIRED_KEYS <= set(record)
    assert {k: record[k] for k in COUNT_KEYS} == {**ZERO, **counts}
    assert record["failed"] == failed and record["ok"] is (not failed)
    assert record["shells"] == shells and len(record["shell_list"]) == shells
    assert record["faces"] == len(triangles) and record["source"] == str(path)
    for key, count in counts.items():  # every problem comes with locations
        if key in record["samples"]:
            assert len(record["samples"][key]) == min(count, 5)


def test_sample_locations_name_faces_and_points(tmp_path):
    path = tmp_path / "open.stl"
    write_binary_stl(path, CUBE[1:])
    record = json.loads(run("check", path, "--json").stdout)
    samples = record["samples"]["boundary_edges"]
    assert {tuple(map(tuple, s["edge"])) for s in samples} == {
        ((0.0, 0.0, 0.0), (1.0, 1.0, 0.0)), ((1.0, 0.0, 0.0), (1.0, 1.0, 0.0)), ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0))}
    assert all(len(s["faces"]) == 1 for s in samples)
    text = run("check", path)
    assert text.exit_code == 1
    assert "FAILED closed" in text.stdout and "3 boundary edges (e.g. face " in text.stdout


def test_clean_and_inward_shell_volumes(tmp_path):
    outer, cavity = CUBE * 4 - 1.5, CUBE[:, ::-1]
    path = tmp_path / "hollow.stl"
    write_ascii_stl(path, np.concatenate([outer, cavity]))
    result = run("check", path, "--json")
    assert result.exit_code == 0
    record = json.loads(result.stdout)
    assert record["volume"] == 63.0 and record["shells"] == 2
    assert [s["volume"] for s in record["shell_list"]] == [64.0, -1.0]
    assert record["format"] == "stl-ascii" and record["closed"] and record["outward"]


def test_human_output_ok_line(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, CUBE)
    result = run("check", path)
    assert result.exit_code == 0
    assert result.stdout.startswith(f"{path}: ok  (stl-binary, 12 faces, 1 shell, volume 1)")
    assert result.stderr == ""  # one input: no summary


def test_require_chooses_the_checks(tmp_path):
    path = tmp_path / "open.stl"
    write_binary_stl(path, CUBE[1:])
    assert run("check", path, "--require", "oriented,manifold").exit_code == 0
    assert run("check", path, "--require", "oriented", "--require", "closed").exit_code == 1
    assert run("check", path, "--require", "none").exit_code == 0
    record = json.loads(run("check", path, "--require", "none", "--json").stdout)
    assert record["required"] == [] and record["ok"] and record["boundary_edges"] == 3


def test_unknown_requirement_is_a_usage_error(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, CUBE)
    result = run("check", path, "--require", "watertight")
    assert result.exit_code == 2
    assert result.stderr.startswith("p3d: error: --require: no check named 'watertight'; checks are: closed,")


def test_limits(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, CUBE * 2)  # volume 8, 12 faces
    assert run("check", path, "--min-volume", "8", "--max-faces", "12").exit_code == 0
    result = run("check", path, "--min-volume", "8.5", "--max-faces", "11", "--json")
    assert result.exit_code == 1
    assert json.loads(result.stdout)["failed"] == ["min-volume", "max-faces"]
    assert run("check", path, "--max-faces", "-1").exit_code == 2


def test_unreadable_inputs_exit_2_with_error_records(tmp_path):
    good, corrupt = tmp_path / "good.stl", tmp_path / "corrupt.stl"
    write_binary_stl(good, CUBE)
    corrupt.write_bytes(good.read_bytes()[:150])  # header says 12 faces, a fraction is there
    missing = tmp_path / "missing.stl"
    result = run("check", good, corrupt, missing, "--json")
    assert result.exit_code == 2
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["source"] for r in records] == [str(good), str(corrupt), str(missing)]
    assert records[0]["ok"] is True and "error" not in records[0]
    assert set(records[1]) == {"schema_version", "source", "ok", "error"} and records[1]["ok"] is False
    assert records[2]["error"] == f"{missing}: no such file; check the path (shape specs are box, wedge, corner, cylinder, sphere, ellipsoid, ecylinder, capsule)"
    assert f"p3d: error: {missing}: no such file" in result.stderr
    assert result.stderr.rstrip().endswith("p3d: 3 files: 1 ok, 2 errors")


def test_failure_and_pass_mixed_exit_1_and_summary(tmp_path):
    good, bad = tmp_path / "a.stl", tmp_path / "b.stl"
    write_binary_stl(good, CUBE)
    write_binary_stl(bad, CUBE[1:])
    result = run("check", tmp_path)
    assert result.exit_code == 1
    assert result.stdout.splitlines()[0].startswith(f"{good}: ok")
    assert "p3d: 2 files: 1 ok, 1 failed check" in result.stderr


def test_csv_header_and_rows(tmp_path):
    good = tmp_path / "a.stl"
    write_binary_stl(good, CUBE[1:])
    result = run("check", good, tmp_path / "nope.stl", "--csv")
    assert result.exit_code == 2
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert rows[0]["source"] == str(good) and rows[0]["ok"] == "false" and rows[0]["failed"] == "closed"
    assert rows[0]["boundary_edges"] == "3" and rows[0]["error"] == ""
    assert rows[1]["source"].endswith("nope.stl") and "no such file" in rows[1]["error"]
    assert run("check", good, "--csv", "--json").exit_code == 2


def test_standard_input(tmp_path):
    path = tmp_path / "cube.stl"
    write_binary_stl(path, CUBE)
    result = run("check", "-", "--format", "stl", "--json", input=path.read_bytes())
    assert result.exit_code == 0
    assert json.loads(result.stdout)["source"] == "-"


def test_no_input_is_a_usage_error():
    result = run("check")
    assert result.exit_code == 2 and "no input given" in result.stderr


def test_non_finite_coordinate_is_an_input_error(tmp_path):
    t = CUBE.copy()
    t[3, 1, 2] = np.nan
    path = tmp_path / "nan.stl"
    write_binary_stl(path, t)
    result = run("check", path)
    assert result.exit_code == 2
    assert result.stderr.startswith(f"p3d: error: {path}: face 3 has a NaN or infinite coordinate")


def test_help_documents_checks_and_exit_statuses():
    result = run("check", "--help")
    assert result.exit_code == 0
    for text in ("Exit statuses:", "0  every mesh passes", "1  some mesh fails", "2  usage error",
                 "--require", "--min-volume", "--max-faces", "--files-from", "--jobs", "--dask", "--csv",
                 "exact", "coordinates"):
        assert text in result.stdout, text


@pytest.mark.parametrize("command", ["props", "bounds", "check"])
def test_an_empty_path_is_named_and_the_shapes_listed(command, tmp_path):
    """An empty argument (an unset shell variable) is said to be one, with a location; a
    missing file's hint lists every shape spec the registry has, not a fixed few."""
    from p3d_cli.shapes import SHAPES

    result = CliRunner().invoke(cli, [command, ""])
    assert result.exit_code == 2
    assert result.stderr == "p3d: error: '': an empty path names no file; give the mesh's path or a shape spec\n"
    result = CliRunner().invoke(cli, [command, str(tmp_path / "gone.stl")])
    assert result.exit_code == 2 and f"shape specs are {', '.join(SHAPES)})" in result.stderr
