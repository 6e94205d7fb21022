"""Warning codes: in messages and JSON, --ignore-warning, thresholds, --strict, project settings."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli import warning_codes
from p3d_cli.warning_codes import CODES, CodedWarning

CUBE = cube_triangles()


@pytest.fixture
def far(tmp_path):
    """A 1 mm float32 cube 100 m from the origin (in mm)."""
    path = tmp_path / "far.stl"
    write_binary_stl(path, CUBE + [1e5, 0, 0])
    return path


def test_every_code_is_documented_and_listed():
    assert {"open", "inward", "flat", "non-manifold", "coarse-float32", "skipped-lines", "unit-slip"} <= set(CODES)
    assert set(warning_codes.THRESHOLDS) <= set(CODES)


@pytest.mark.parametrize("triangles, code", [
    (CUBE[2:], "open"), (CUBE[:, ::-1], "inward"), (np.zeros((2, 3, 3)) + np.eye(3)[[0, 1, 1]], "flat")])
def test_json_lists_codes_beside_the_warnings(tmp_path, triangles, code):
    path = tmp_path / "part.stl"
    write_binary_stl(path, triangles)
    result = run("props", path, "--json")
    record = json.loads(result.stdout)
    assert len(record["warning_codes"]) == len(record["warnings"]) >= 1
    assert code in record["warning_codes"]
    assert f"p3d: warning: [{code}] {path}: " in result.stderr


def test_far_float32_part_passes_strict_once_its_warning_is_ignored(far):
    strict = run("props", far, "--strict")
    assert strict.exit_code == 1 and "[coarse-float32]" in strict.stderr
    ignored = run("props", far, "--strict", "--ignore-warning", "coarse-float32")
    assert ignored.exit_code == 0, ignored.stderr
    assert "warning" not in ignored.stderr
    # the record still says what it found
    record = json.loads(run("props", far, "--json", "--ignore-warning", "coarse-float32").stdout)
    assert record["warning_codes"] == ["coarse-float32"]


def test_threshold_silences_a_warning_within_it_only(far):
    # the warning's measure: largest |coordinate| * 2**-23 (float32's relative spacing) / diagonal
    ratio = (1e5 + 1) * 2.0 ** -23 / np.sqrt(3)
    assert run("props", far, "--strict", "--warning-threshold", f"coarse-float32={ratio * 1.01}").exit_code == 0
    assert run("props", far, "--strict", "--warning-threshold", f"coarse-float32={ratio * 0.99}").exit_code == 1
    below = run("props", far, "--warning-threshold", "coarse-float32=1e-9")
    assert below.exit_code == 2 and "can only be raised" in below.stderr
    assert run("props", far, "--warning-threshold", "open=1").exit_code == 2


def test_strict_counts_only_warnings_not_ignored(tmp_path, far):
    open_part = tmp_path / "open.stl"
    write_binary_stl(open_part, CUBE[2:])
    result = run("props", far, open_part, "--strict", "--ignore-warning", "coarse-float32")
    assert result.exit_code == 1
    assert "1 ok, 1 with warnings (--strict)" in result.stderr
    assert result.stderr.count("p3d: warning: ") == 1 and "[open]" in result.stderr


def test_unknown_code_is_a_usage_error(far):
    result = run("props", far, "--ignore-warning", "coarse")
    assert result.exit_code == 2 and "--ignore-warning" in result.stderr


def test_coded_warning_is_a_string_that_pickles_with_its_code():
    w = CodedWarning("mesh is not closed", "open", 0.5)
    back = pickle.loads(pickle.dumps(w))
    assert back == "mesh is not closed" and back.code == "open" and back.value == 0.5
    with pytest.raises(ValueError):
        CodedWarning("x", "no-such-code")


def test_library_results_carry_codes(far):
    import p3d_cli as p3d

    result = p3d.props(str(far))
    assert result.warning_codes == ("coarse-float32",)
    assert p3d.bounds("box").warning_codes == ()


def test_project_settings_ignore_and_density_by_glob(tmp_path, monkeypatch):
    heavy = tmp_path / "steel"
    heavy.mkdir()
    write_binary_stl(heavy / "a.stl", CUBE)
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    (tmp_path / "p3d.toml").write_text('ignore-warnings = ["open"]\n\n'
                                       '[[paths]]\nglob = "steel/*.stl"\ndensity = 7850\n')
    monkeypatch.chdir(tmp_path)
    assert run("props", "open.stl", "--strict").exit_code == 0
    assert run("props", "open.stl", "--strict", "--no-config").exit_code == 1
    assert json.loads(run("props", "steel/a.stl", "--json").stdout)["mass"] == 7850.0
    assert json.loads(run("props", "steel/a.stl", "--json", "--density", "2").stdout)["mass"] == 2.0
    assert json.loads(run("props", "open.stl", "--json").stdout)["density"] == 1.0


def test_settings_in_pyproject_found_from_a_subfolder(tmp_path, monkeypatch):
    (tmp_path / "pyproject.toml").write_text('[project]\nname = "x"\n\n[tool.p3d]\n'
                                             'warning-thresholds = { coarse-float32 = 1.0 }\n')
    sub = tmp_path / "a" / "b"
    sub.mkdir(parents=True)
    write_binary_stl(sub / "far.stl", CUBE + [1e5, 0, 0])
    monkeypatch.chdir(sub)
    assert run("props", "far.stl", "--strict").exit_code == 0
    assert run("props", "far.stl", "--strict", "--no-config").exit_code == 1


def test_bad_settings_are_one_clear_error(tmp_path, monkeypatch):
    (tmp_path / "p3d.toml").write_text("densty = 3\n")
    monkeypatch.chdir(tmp_path)
    result = run("props", "box")
    assert result.exit_code == 2
    assert "p3d.toml: densty: unknown p3d setting" in result.stderr and "Traceback" not in result.output
    (tmp_path / "p3d.toml").write_text("density = [\n")
    assert "not valid TOML" in run("props", "box").stderr


def test_check_requirements_by_glob(tmp_path, monkeypatch):
    (tmp_path / "scans").mkdir()
    write_binary_stl(tmp_path / "scans" / "open.stl", CUBE[2:])
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    (tmp_path / "p3d.toml").write_text('[[paths]]\nglob = "scans/*"\nrequire = ["outward"]\n')
    monkeypatch.chdir(tmp_path)
    assert run("check", "scans/open.stl").exit_code == 0            # scans need only be outward
    assert run("check", "open.stl").exit_code == 1                  # everything else: every check
    assert run("check", "scans/open.stl", "--no-config").exit_code == 1
    assert run("check", "scans/open.stl", "--require", "closed").exit_code == 1   # the command line wins


def test_library_warnings_get_their_own_codes_not_the_fallback():
    import p3d_cli as p3d

    tilted = p3d.Placement(rotation=p3d.rotation_from_quaternion(0.3, 0.5, -0.7, 0.2))
    few = p3d.props("box:1,1,0.001", tilted, method="montecarlo", samples=2000, seed=1)
    assert "montecarlo-few-inside" in few.warning_codes or "montecarlo-empty" in few.warning_codes
    slip = p3d.props("box:50,40,5", density=7850)  # a millimetre-sized part, a kg/m³ density
    assert "unit-slip" in slip.warning_codes
    assert "reader" not in few.warning_codes + slip.warning_codes
