"""Reports and summaries never damage an input and never outlive the run that wrote them (issue 27,
item 1): written whole through p3d_cli.io.atomic, refused over an input, and marked incomplete
from the start of a run, so that a run killed or interrupted part way never leaves the previous
run's "all passed" for CI to publish."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl

CUBE = cube_triangles()


@pytest.fixture
def parts(tmp_path):
    for name in ("a.stl", "b.stl", "c.stl"):
        write_binary_stl(tmp_path / name, CUBE)
    return tmp_path


@pytest.mark.parametrize("option", ["--report", "--summary"])
def test_a_report_naming_an_input_is_refused_and_the_input_kept(parts, option):
    before = (parts / "b.stl").read_bytes()
    value = f"junit:{parts / 'b.stl'}" if option == "--report" else f"json:{parts / 'b.stl'}"
    result = run("check", parts / "a.stl", parts / "b.stl", option, value)
    assert result.exit_code == 2
    assert "would overwrite the input" in result.output and "b.stl" in result.output
    assert (parts / "b.stl").read_bytes() == before
    assert "ok" not in result.stdout   # refused before any input was read


def test_a_report_naming_a_file_inside_a_directory_input_is_refused(parts):
    before = (parts / "c.stl").read_bytes()
    result = run("check", parts, "--report", f"github:{parts / 'c.stl'}")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    assert (parts / "c.stl").read_bytes() == before


def test_a_report_over_the_files_from_list_or_the_baseline_is_refused(parts):
    listing = parts / "list.txt"
    listing.write_text(f"{parts / 'a.stl'}\n")
    result = run("check", "--files-from", listing, "--report", f"junit:{listing}")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    assert listing.read_text() == f"{parts / 'a.stl'}\n"
    base = parts / "base.ndjson"
    assert run("props", parts / "a.stl", "--json").exit_code == 0
    base.write_text(run("props", parts / "a.stl", "--json").stdout)
    kept = base.read_text()
    result = run("diff", base, parts / "a.stl", "--summary", f"json:{base}")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    assert base.read_text() == kept


def test_diff_update_never_writes_the_baseline_over_a_mesh(parts):
    before = (parts / "a.stl").read_bytes()
    result = run("diff", parts / "a.stl", parts / "a.stl", "--update")
    assert result.exit_code == 2 and "would overwrite the input" in result.output
    assert (parts / "a.stl").read_bytes() == before


def test_an_interrupted_run_leaves_an_incomplete_report_not_the_last_pass(parts, monkeypatch, tmp_path):
    junit, summary, github = tmp_path / "r.xml", tmp_path / "s.json", tmp_path / "g.txt"
    options = ["--report", f"junit:{junit}", "--summary", f"json:{summary}", "--report", f"github:{github}"]
    assert run("check", parts / "a.stl", parts / "b.stl", parts / "c.stl", *options).exit_code == 0
    assert json.loads(summary.read_text())["complete"] is True
    assert ET.parse(junit).getroot().get("errors") == "0"

    # Ctrl-C while the second input is being checked.
    from p3d_cli import measure

    real = measure.check
    calls = []

    def interrupted(thing, **kwargs):
        calls.append(thing)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(thing, **kwargs)

    monkeypatch.setattr(measure, "check", interrupted)
    result = run("check", parts / "a.stl", parts / "b.stl", parts / "c.stl", "--jobs", "1", *options)
    assert result.exit_code == 130
    record = json.loads(summary.read_text())
    assert record["complete"] is False and record["exit_status"] is None
    root = ET.parse(junit).getroot()
    assert root.get("errors") == "1" and root.get("failures") == "0"
    assert "did not finish" in root.find("testsuite/testcase/error").get("message")
    assert github.read_text().startswith("::error ") and "did not finish" in github.read_text()
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".p3d-tmp")]


def test_a_killed_run_leaves_an_incomplete_report(parts, tmp_path):
    """SIGKILL gives no chance to clean up: the report is marked incomplete before the run starts."""
    fifo = tmp_path / "blocks.stl"
    os.mkfifo(fifo)
    summary = tmp_path / "s.json"
    summary.write_text(json.dumps({"complete": True, "exit_status": 0}))
    child = subprocess.Popen([sys.executable, "-m", "p3d_cli", "check", str(parts / "a.stl"), str(fifo),
                              "--jobs", "1", "--summary", f"json:{summary}"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and json.loads(summary.read_text()).get("complete") is not False:
            time.sleep(0.05)
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
    assert json.loads(summary.read_text()) == {"schema_version": 1, "command": "p3d check", "complete": False,
                                               "exit_status": None}


def test_combine_writes_its_report_and_summary(parts, tmp_path):
    """--combine is one result: its report replaces the incomplete one written at the start."""
    summary = tmp_path / "s.json"
    result = run("props", parts / "a.stl", parts / "b.stl", "--combine", "--summary", f"json:{summary}")
    assert result.exit_code == 0, result.output
    record = json.loads(summary.read_text())
    assert (record["complete"], record["inputs"], record["ok"], record["exit_status"]) == (True, 1, 1, 0)
