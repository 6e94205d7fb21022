"""The project settings file (p3d.toml): what it changes is applied and named, and its errors
name the file and the key (issue 24 item 2; issue 27 item 4)."""

from __future__ import annotations

import json

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl

CUBE = cube_triangles()   # the unit cube: volume 1


@pytest.fixture
def project(tmp_path, monkeypatch):
    (tmp_path / "steel").mkdir()
    write_binary_stl(tmp_path / "a.stl", CUBE)
    write_binary_stl(tmp_path / "steel" / "b.stl", CUBE * 2.0)   # volume 8
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_combine_with_a_paths_entry_gives_each_part_its_density(project):
    (project / "p3d.toml").write_text('density = 2\n\n[[paths]]\nglob = "steel/*.stl"\ndensity = 7\n')
    result = run("props", "a.stl", "steel/b.stl", "--combine", "--json")
    assert result.exit_code == 0, result.output
    record = json.loads(result.stdout)
    assert [part["mass"] for part in record["parts"]] == [2.0, 56.0]
    assert record["mass"] == 58.0
    assert record["settings"]["file"] == str(project / "p3d.toml")
    # the command line still wins over every part's setting
    record = json.loads(run("props", "a.stl", "steel/b.stl", "--combine", "--json", "--density", "1").stdout)
    assert record["mass"] == 9.0


def test_units_in_the_settings_are_applied_with_a_density_with_its_unit(project):
    (project / "p3d.toml").write_text('units = "mm"\ndensity = "8 g/cm^3"\n')
    result = run("props", "a.stl", "--json")
    assert result.exit_code == 0, result.output
    record = json.loads(result.stdout)
    assert record["units"]["mesh_length"] == "mm" and record["units"]["mass"] == "kg"
    assert record["mass"] == pytest.approx(8e-6, rel=1e-12)        # 1 mm³ of 8 g/cm³
    assert record["settings"] == {"file": str(project / "p3d.toml"), "keys": ["density", "units"]}
    text = run("props", "a.stl")
    assert "p3d: settings: " in text.stderr and "p3d.toml" in text.stderr and "(density, units)" in text.stderr
    bounds = json.loads(run("bounds", "a.stl", "--json").stdout)
    assert bounds["max"] == pytest.approx([0.001] * 3)            # in metres, from the file's mm


def test_no_settings_key_and_no_line_without_a_file(project):
    record = json.loads(run("props", "a.stl", "--json").stdout)
    assert record["settings"] is None
    assert "settings" not in run("props", "a.stl").stderr


def test_a_setting_the_command_line_overrides_is_not_named(project):
    (project / "p3d.toml").write_text("density = 5\n")
    record = json.loads(run("props", "a.stl", "--json", "--density", "3").stdout)
    assert record["mass"] == 3.0 and record["settings"] is None


@pytest.mark.parametrize("text, where, what", [
    ('density = "8 g/cm^3"\n', "p3d.toml: density", "has a unit, but no length unit is set"),
    ('units = "mm"\ndensity = 7850\n', "p3d.toml: density", "has no unit"),
    ('units = "furlong"\n', "p3d.toml: units", "unknown length unit"),
    ('density = "heavy"\n', "p3d.toml: density", "is not a quantity"),
    ('density = "7850"\n', "p3d.toml: density", "text without a unit"),
    ('density = "3 kg"\n', "p3d.toml: density", "is not a density"),
    ('require = ["closed", 5]\n', "p3d.toml: require", "5 is not a name"),
    ('require = ["closd"]\n', "p3d.toml: require", "no check named 'closd'"),
    ('ignore-warnings = ["nope"]\n', "p3d.toml: ignore-warnings", "no warning code 'nope'"),
    ('warning-thresholds = { coarse-float32 = "x" }\n', "p3d.toml: warning-thresholds.coarse-float32",
     "not a non-negative number"),
    ('warning-thresholds = { coarse-float32 = 1e-9 }\n', "p3d.toml: warning-thresholds", "below p3d's"),
    ('rtol = { volum = 1e-3 }\n', "p3d.toml: rtol", "no quantity 'volum'"),
    ('[[paths]]\nglob = "*.stl"\ndensity = -1\n', "p3d.toml: paths[0].density", "not a positive"),
])
def test_settings_errors_name_the_file_and_the_key_never_a_flag(project, text, where, what):
    (project / "p3d.toml").write_text(text)
    command = "diff" if "rtol" in text else "check" if "require" in text else "props"
    args = [command, "base.ndjson", "a.stl"] if command == "diff" else [command, "a.stl"]
    (project / "base.ndjson").write_text("")
    result = run(*args)
    assert result.exit_code == 2, result.output
    line = result.stderr.strip()
    assert line.count("\n") == 0 and "Traceback" not in result.output
    assert where in line and what in line, line
    assert "--density" not in line.split(";")[0] and "--units" not in line.split(";")[0] and "--rtol" not in line


def test_config_show_prints_the_file_and_each_inputs_settings(project):
    assert "no settings file" in run("config", "--show").stdout
    (project / "p3d.toml").write_text('density = 2\n\n[[paths]]\nglob = "steel/*.stl"\ndensity = 7\n')
    shown = run("config", "--show", "steel/b.stl", "a.stl")
    assert shown.exit_code == 0
    assert f"settings file: {project / 'p3d.toml'}" in shown.stdout
    assert "steel/b.stl: density = 7" in shown.stdout and "a.stl: density = 2" in shown.stdout
    record = json.loads(run("config", "--json", "steel/b.stl").stdout)
    assert record["file"] == str(project / "p3d.toml") and record["inputs"][0]["settings"] == {"density": 7}
    (project / "p3d.toml").write_text('require = ["closed", 5]\n')
    bad = run("config", "--show")
    assert bad.exit_code == 2 and "p3d.toml: require: 5 is not a name" in bad.stderr


def test_check_names_the_settings_that_chose_its_requirements(project):
    (project / "p3d.toml").write_text('require = ["closed"]\n')
    record = json.loads(run("check", "a.stl", "--json").stdout)
    assert record["required"] == ["closed"] and record["settings"]["keys"] == ["require"]
    assert "p3d: settings:" in run("check", "a.stl").stderr
    assert json.loads(run("check", "a.stl", "--json", "--require", "all").stdout)["settings"] is None
