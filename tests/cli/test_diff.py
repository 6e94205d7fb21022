"""``p3d diff``: a baseline of a folder, then planted changes, each reported alone with exit 1."""

from __future__ import annotations

import json
import os
import shutil

import pytest
from click.testing import CliRunner

from conftest import cube_triangles, write_binary_stl
from p3d_cli.cli.main import cli

CUBE = cube_triangles()


def run(*args, input=None):
    return CliRunner().invoke(cli, [str(a) for a in args], input=input)


def part(i: int):
    return CUBE * (i + 1) + [0.3, 0.1, 0.2]


@pytest.fixture
def project(tmp_path, monkeypatch):
    """parts/p0..p3.stl and their baseline, made in the project's root (the working directory)."""
    (tmp_path / "parts").mkdir()
    for i in range(4):
        write_binary_stl(tmp_path / "parts" / f"p{i}.stl", part(i))
    monkeypatch.chdir(tmp_path)
    made = run("props", "parts", "--json")
    assert made.exit_code == 0
    (tmp_path / "baseline.ndjson").write_text(made.stdout)
    return tmp_path


def changed_lines(result) -> list[str]:
    return [line for line in result.stdout.splitlines() if line]


def test_unchanged_folder_passes_quietly(project):
    result = run("diff", "baseline.ndjson", "parts")
    assert result.exit_code == 0 and result.stdout == ""
    assert "4 files: 4 ok" in result.stderr


def test_baseline_works_from_another_checkout(project, tmp_path_factory, monkeypatch):
    other = tmp_path_factory.mktemp("elsewhere")
    shutil.copytree(project / "parts", other / "parts")
    shutil.copy(project / "baseline.ndjson", other / "b.ndjson")
    monkeypatch.chdir(other)
    assert run("diff", "b.ndjson", "parts").exit_code == 0
    monkeypatch.chdir(project.parent)
    assert run("diff", other / "b.ndjson", other / "parts", "--root", other).exit_code == 0


def test_scale_by_1_0001_is_reported_for_that_file_only(project):
    write_binary_stl(project / "parts" / "p1.stl", part(1) * 1.0001)
    result = run("diff", "baseline.ndjson", "parts")
    assert result.exit_code == 1
    lines = changed_lines(result)
    assert lines and all(line.startswith("parts/p1.stl: ") for line in lines)
    volume = next(line for line in lines if line.startswith("parts/p1.stl: volume "))
    assert "-> " in volume and volume.endswith(" (+0.03%)")        # 1.0001**3 - 1 = 3.0003e-4
    assert all(len(line) <= 80 for line in lines), lines           # vectors by their largest change
    records = [json.loads(line) for line in run("diff", "baseline.ndjson", "parts", "--json").stdout.splitlines()]
    vol = next(r for r in records if r["quantity"] == "volume")
    assert vol["new"] / vol["old"] == pytest.approx(1.0001 ** 3, rel=1e-6)
    assert vol["relative_change"] == pytest.approx((vol["new"] - vol["old"]) / vol["old"], rel=1e-12)
    assert vol["relative_change"] == pytest.approx(1.0001 ** 3 - 1, rel=1e-2)   # float32 coordinates
    # a tolerance above the change lets it pass; one below does not
    assert run("diff", "baseline.ndjson", "parts", "--rtol", "1e-3").exit_code == 0
    assert run("diff", "baseline.ndjson", "parts", "--rtol", "1e-3", "--rtol", "volume=1e-4").exit_code == 1


def test_flipped_file_is_reported(project):
    write_binary_stl(project / "parts" / "p2.stl", part(2)[:, ::-1])
    result = run("diff", "baseline.ndjson", "parts", "--json")
    assert result.exit_code == 1
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert {r["source"] for r in records} == {"parts/p2.stl"}
    # Issue 12.6: an inward-wound file is measured as the solid it encloses, so its volume
    # does not change sign; the flip shows as the new "inward" warning.
    assert not any(r["quantity"] == "volume" for r in records)
    assert any(r["quantity"] == "warning_codes" and r["new"] == ["inward"] for r in records)


def test_new_open_mesh_appears(project):
    write_binary_stl(project / "parts" / "new.stl", CUBE[2:])
    result = run("diff", "baseline.ndjson", "parts")
    assert result.exit_code == 1
    assert changed_lines(result) == ["parts/new.stl: appeared (not in the baseline)"]


def test_mesh_that_stopped_being_closed(project):
    write_binary_stl(project / "parts" / "p0.stl", part(0)[2:])
    result = run("diff", "baseline.ndjson", "parts", "--json")
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert result.exit_code == 1 and {r["source"] for r in records} == {"parts/p0.stl"}
    assert {"quantity": "closed", "old": True, "new": False}.items() <= next(
        r for r in records if r["quantity"] == "closed").items()


def test_truncated_file_is_reported(project):
    path = project / "parts" / "p3.stl"
    path.write_bytes(path.read_bytes()[:300])
    result = run("diff", "baseline.ndjson", "parts")
    assert result.exit_code == 1
    [line] = changed_lines(result)
    assert line.startswith("parts/p3.stl: cannot be read now: ") and "truncated" in line


def test_removed_file_vanishes(project):
    os.remove(project / "parts" / "p0.stl")
    result = run("diff", "baseline.ndjson", "parts")
    assert result.exit_code == 1
    assert changed_lines(result) == ["parts/p0.stl: vanished (in the baseline, not found)"]


def test_update_rewrites_the_baseline(project):
    write_binary_stl(project / "parts" / "p1.stl", part(1) * 2)
    os.remove(project / "parts" / "p0.stl")
    assert run("diff", "baseline.ndjson", "parts", "--update").exit_code == 0
    keys = [json.loads(line)["source"] for line in (project / "baseline.ndjson").read_text().splitlines()]
    assert keys == ["parts/p1.stl", "parts/p2.stl", "parts/p3.stl"]
    assert run("diff", "baseline.ndjson", "parts").exit_code == 0


def test_bad_baseline_and_bad_tolerance_are_clear_errors(project):
    (project / "bad.ndjson").write_text("{not json\n")
    bad = run("diff", "bad.ndjson", "parts")
    assert bad.exit_code == 2 and "bad.ndjson:1: not a JSON line" in bad.stderr
    missing = run("diff", "nope.ndjson", "parts")
    assert missing.exit_code == 2 and "nope.ndjson: no such file" in missing.stderr
    tolerance = run("diff", "baseline.ndjson", "parts", "--rtol", "volum=1")
    assert tolerance.exit_code == 2 and "no quantity 'volum'" in tolerance.stderr


def test_tolerances_from_project_settings_by_glob(project):
    write_binary_stl(project / "parts" / "p1.stl", part(1) * 1.0001)
    (project / "p3d.toml").write_text('[[paths]]\nglob = "parts/p1.stl"\nrtol = { volume = 1e-3, mass = 1e-3, '
                                      'center_of_mass = 1e-3, inertia = 1e-3, principal_moments = 1e-3, '
                                      '"bounds.min" = 1e-3, "bounds.max" = 1e-3 }\n')
    assert run("diff", "baseline.ndjson", "parts").exit_code == 0
    assert run("diff", "baseline.ndjson", "parts", "--no-config").exit_code == 1
    assert run("diff", "baseline.ndjson", "parts", "--rtol", "inertia=1e-6").exit_code == 1   # command line wins
