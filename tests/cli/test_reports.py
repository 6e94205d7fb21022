"""Reports CI systems read: JUnit XML (parsed and validated against the JUnit schema), GitHub
workflow-command annotations, and the JSON summary, from check, props --strict and diff."""

from __future__ import annotations

import json
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl

CUBE = cube_triangles()
SCHEMA = Path(__file__).with_name("data") / "junit.xsd"
#: The documented syntax: ::error file=NAME,title=TITLE::MESSAGE, properties and data escaped.
ANNOTATION = re.compile(r"^::(error|warning) file=[^,:\n]+,title=[^,:\n]+::[^\n]+$")


@pytest.fixture
def folder(tmp_path):
    """good.stl, open.stl (fails check), corrupt.stl (cannot be read), notes.fbx (skipped)."""
    parts = tmp_path / "parts"
    parts.mkdir()
    write_binary_stl(parts / "good.stl", CUBE)
    write_binary_stl(parts / "open.stl", CUBE[2:])
    (parts / "corrupt.stl").write_bytes(b"\0" * 80 + b"\x05\0\0\0" + b"\0" * 10)
    (parts / "notes.fbx").write_bytes(b"PK")
    return parts


def validate(path: Path):
    lxml = pytest.importorskip("lxml.etree")
    schema = lxml.XMLSchema(lxml.parse(str(SCHEMA)))
    document = lxml.parse(str(path))
    assert schema.validate(document), schema.error_log
    return ET.parse(path).getroot()


def test_junit_from_check_has_one_testcase_per_input_and_the_right_counts(folder, tmp_path):
    report = tmp_path / "check.xml"
    result = run("check", folder, "--report", f"junit:{report}")
    assert result.exit_code == 2
    root = validate(report)
    suite = root.find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors"), suite.get("skipped")) == ("4", "1", "1", "1")
    cases = {Path(c.get("name")).name: c for c in suite.iter("testcase")}
    assert set(cases) == {"good.stl", "open.stl", "corrupt.stl", "notes.fbx"}
    assert list(cases["good.stl"]) == []
    failure = cases["open.stl"].find("failure")
    assert failure.get("type") == "closed" and "boundary edge" in failure.get("message")
    assert "binary STL" in cases["corrupt.stl"].find("error").get("message")
    assert cases["notes.fbx"].find("skipped") is not None
    assert all(c.get("classname") == "p3d.check" for c in cases.values())


def test_junit_from_props_strict_lists_warnings(folder, tmp_path):
    report = tmp_path / "props.xml"
    (folder / "corrupt.stl").unlink()
    result = run("props", folder, "--strict", "--report", f"junit:{report}")
    assert result.exit_code == 1
    suite = validate(report).find("testsuite")
    assert (suite.get("tests"), suite.get("failures"), suite.get("errors")) == ("3", "1", "0")
    failed = next(c for c in suite.iter("testcase") if c.find("failure") is not None)
    assert failed.get("name").endswith("open.stl") and failed.find("failure").get("type") == "open"


def test_github_annotations_follow_the_documented_syntax(folder, tmp_path):
    out = tmp_path / "annotations.txt"
    result = run("check", folder, "--report", f"github:{out}")
    lines = out.read_text().splitlines()
    assert result.exit_code == 2 and len(lines) == 2
    assert all(ANNOTATION.match(line) for line in lines), lines
    assert lines[0].startswith("::error file=") and "corrupt.stl,title=p3d check [error]::" in lines[0]
    assert "open.stl,title=p3d check [closed]::" in lines[1]


def test_github_on_stdout_escapes_names_and_messages(tmp_path):
    odd = tmp_path / "a,b:c.stl"
    write_binary_stl(odd, CUBE[2:])
    result = run("props", odd, "--report", "github")
    [line] = [line for line in result.stdout.splitlines() if line.startswith("::")]
    assert ANNOTATION.match(line)
    assert "a%2Cb%3Ac.stl,title=p3d props [open]::mesh is not closed" in line


def test_summary_counts_every_state(folder, tmp_path):
    write_binary_stl(folder / "inward.stl", CUBE[:, ::-1])
    summary = tmp_path / "summary.json"
    result = run("props", folder, "--summary", f"json:{summary}")
    counts = json.loads(summary.read_text())
    assert result.exit_code == 2
    assert {k: counts[k] for k in ("inputs", "ok", "warned", "failed", "errored", "skipped")} == \
        {"inputs": 4, "ok": 1, "warned": 2, "failed": 0, "errored": 1, "skipped": 1}
    assert counts["warnings_by_code"] == {"inward": 1, "open": 1} and counts["exit_status"] == 2


def test_diff_reports_changed_files_as_failures(tmp_path, monkeypatch):
    (tmp_path / "parts").mkdir()
    write_binary_stl(tmp_path / "parts" / "a.stl", CUBE)
    write_binary_stl(tmp_path / "parts" / "b.stl", CUBE * 2)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "base.ndjson").write_text(run("props", "parts", "--json").stdout)
    write_binary_stl(tmp_path / "parts" / "b.stl", CUBE * 3)
    result = run("diff", "base.ndjson", "parts", "--report", "junit:d.xml", "--report", "github:g.txt")
    assert result.exit_code == 1
    suite = validate(tmp_path / "d.xml").find("testsuite")
    assert (suite.get("tests"), suite.get("failures")) == ("2", "1")
    assert all(ANNOTATION.match(line) and "parts/b.stl" in line for line in (tmp_path / "g.txt").read_text().splitlines())


def test_bad_report_kinds_are_usage_errors(folder):
    assert run("check", folder, "--report", "xml:x").exit_code == 2
    assert run("check", folder, "--report", "junit").exit_code == 2
    assert run("check", folder, "--summary", "yaml:x").exit_code == 2


def test_page_reports_are_prepared_like_the_others(tmp_path):
    """html:DIR and github-summary:FILE go through prepare_reports too (they were unknown to it):
    an existing report folder's page says the run is incomplete until the run ends; a summary,
    which is appended to, is left alone; a page path naming an input is refused first."""
    from p3d_cli.cli.reports import INCOMPLETE, parse_reports, prepare_reports
    from p3d_cli.errors import OutputError

    folder = tmp_path / "report"
    folder.mkdir()
    (folder / "index.html").write_text("<p>all passed</p>")
    summary = tmp_path / "summary.md"
    summary.write_text("earlier step\n")
    options = parse_reports([f"html:{folder}", f"github-summary:{summary}"], None)
    prepare_reports(options, "check", inputs=["part.stl"])
    assert INCOMPLETE in (folder / "index.html").read_text()
    assert summary.read_text() == "earlier step\n"
    mesh = tmp_path / "part.stl"
    mesh.write_bytes(b"solid")
    with pytest.raises(OutputError, match="would overwrite the input"):
        prepare_reports(parse_reports([f"github-summary:{mesh}"], None), "check", inputs=[str(mesh)])
    assert mesh.read_bytes() == b"solid"
