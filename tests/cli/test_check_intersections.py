"""``p3d check``'s no-self-intersection and nesting checks, --weld, and ``p3d props`` --shells."""

from __future__ import annotations

import json

import numpy as np
import pytest

import p3d_cli as p3d
from helpers.cli import run
from helpers.meshes import write_ascii_stl, write_binary_stl
from helpers.solids import box


OVERLAP = np.concatenate([box([0, 0, 0], [2, 2, 2]), box([1, 1, 1], [3, 3, 3])])
HOLLOW = np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2], inward=True)])
NESTED = np.concatenate([box([0, 0, 0], [3, 3, 3]), box([1, 1, 1], [2, 2, 2])])
TOUCHING = np.concatenate([box([0, 0, 0], [1, 1, 1]), box([1, 0, 0], [2, 1, 1], [True] * 6)])


def test_overlapping_bodies_fail_with_pairs_and_points(tmp_path):
    path = tmp_path / "overlap.stl"
    write_binary_stl(path, OVERLAP)
    result = run("check", path)
    assert result.exit_code == 1
    assert "FAILED no-self-intersection, nesting" in result.stdout
    assert "6 self-intersecting face pairs (e.g. faces 2,17 cross at (1.5, 1, 2);" in result.stdout
    assert "shell 0 (12 faces from face 0) and shell 1 (12 faces from face 12) cross" in result.stdout
    assert "volume counted twice: 0 + at most 1 where shells cross" in result.stdout
    record = json.loads(run("check", path, "--json").stdout)
    found = record["self_intersections"]
    assert found["count"] == 6 and found["by_kind"] == {"crossing": 6, "overlap": 0, "fold": 0}
    assert found["samples"][0] == {"faces": [2, 17], "kind": "crossing", "point": [1.5, 1.0, 2.0]}
    assert record["nesting"]["relations"] == [{"shell": 0, "other": 1, "relation": "crossing"}]
    assert record["failed"] == ["no-self-intersection", "nesting"]


def test_touching_bodies_and_a_hollow_part_pass(tmp_path):
    for name, triangles, failed in (("touching", TOUCHING, ["closed", "manifold"]), ("hollow", HOLLOW, [])):
        path = tmp_path / f"{name}.stl"
        write_binary_stl(path, triangles)
        record = json.loads(run("check", path, "--json").stdout)
        assert record["self_intersections"]["count"] == 0 and record["nesting"]["ok"]
        assert record["failed"] == failed


def test_a_body_inside_another_wound_alike_fails_nesting(tmp_path):
    path = tmp_path / "nested.stl"
    write_binary_stl(path, NESTED)
    result = run("check", path)
    assert result.exit_code == 1 and "FAILED nesting" in result.stdout
    assert "lies inside shell 0 (12 faces from face 0) and" in result.stdout
    assert "volume counted twice: 1" in result.stdout


def test_the_checks_are_named_and_skipped_when_not_required(tmp_path):
    path = tmp_path / "overlap.stl"
    write_binary_stl(path, OVERLAP)
    record = json.loads(run("check", path, "--json", "--require", "closed,outward").stdout)
    assert record["ok"] and record["self_intersections"] is None and record["nesting"] is None
    record = json.loads(run("check", path, "--json", "--require", "no-self-intersection").stdout)
    assert record["failed"] == ["no-self-intersection"] and record["nesting"] is not None
    assert "no-self-intersection" in run("check", "--help").stdout
    bad = run("check", path, "--require", "no-self-intersections")
    assert bad.exit_code == 2 and "no-self-intersection" in bad.stderr


def test_csv_has_the_count(tmp_path):
    path = tmp_path / "overlap.stl"
    write_binary_stl(path, OVERLAP)
    lines = run("check", path, "--csv").stdout.splitlines()
    header, row = lines[0].split(","), lines[1].split(",")
    assert row[header.index("self_intersections")] == "6"


def test_weld_closes_a_seam_that_exact_matching_leaves_open(tmp_path):
    rng = np.random.default_rng(3)
    cube = box([0, 0, 0], [1, 1, 1])
    noisy = cube + rng.uniform(-1e-7, 1e-7, cube.shape) * (cube == 1)
    path = tmp_path / "seams.stl"
    write_ascii_stl(path, noisy)
    plain = json.loads(run("check", path, "--json").stdout)
    assert not plain["closed"] and "weld" not in plain
    welded = json.loads(run("check", path, "--json", "--weld", "1e-6").stdout)
    assert welded["closed"] and welded["ok"]
    assert welded["weld"]["vertices"] > 0 and 0 < welded["weld"]["largest_distance"] <= 2 * 3 ** 0.5 * 1e-7
    text = run("check", path, "--weld", "1e-6").stdout
    assert f"welded {welded['weld']['vertices']} vertices within 1e-06" in text
    assert run("check", path, "--weld", "0").exit_code == 2
    assert p3d.check(noisy, weld=1e-6).weld.vertices == welded["weld"]["vertices"]


def test_the_api_carries_the_same(tmp_path):
    result = p3d.check(OVERLAP)
    assert result.report.self_intersections.count == 6 and not result.report.nesting.ok
    pairs = p3d.self_intersections(OVERLAP)
    assert pairs.pairs.shape == (6, 2) and pairs.kinds == ("crossing",) * 6
    assert p3d.self_intersections(TOUCHING).count == 0


def test_props_warns_with_stable_codes(tmp_path):
    overlap = p3d.props(OVERLAP, intersections=True)
    assert overlap.warning_codes == ("self-intersecting",)
    assert "the surface intersects itself: 6 face pairs cross or overlap" in overlap.warnings[0]
    assert p3d.props(OVERLAP).warnings == ()              # not asked: props stays as fast as before
    nested = p3d.props(NESTED, intersections=True)
    assert nested.warning_codes == ("nested-shells",) and "counted 2 times" in nested.warnings[0]
    assert p3d.props(HOLLOW, intersections=True).warnings == ()


def test_props_shells_measures_each_body(tmp_path):
    path = tmp_path / "hollow.stl"
    write_binary_stl(path, np.concatenate([HOLLOW, box([5, 0, 0], [6, 1, 1])]))
    record = json.loads(run("props", path, "--shells", "--json").stdout)
    parts = {p["name"]: p["volume"] for p in record["parts"]}
    assert parts == {"shell 0 with cavity 1": 26.0, "shell 2": 1.0}
    assert record["volume"] == 27.0 and record["warning_codes"] == []
    path = tmp_path / "nested.stl"
    write_binary_stl(path, NESTED)
    result = run("props", path, "--shells")
    assert "part shell 0:" in result.stdout and "part shell 1:" in result.stdout
    assert "[nested-shells]" in result.stderr
    strict = run("props", path, "--shells", "--strict")
    assert strict.exit_code == 1
    assert run("props", path, "--shells", "--ignore-warning", "nested-shells", "--strict").exit_code == 0


@pytest.mark.parametrize("args", [["--shells", "--combine"]])
def test_props_refuses_shells_with_combine(tmp_path, args):
    path = tmp_path / "a.stl"
    write_binary_stl(path, HOLLOW)
    result = run("props", path, path, *args)
    assert result.exit_code == 2 and "--shells/--combine" in result.stderr
