"""docs/ci.md cannot drift: its gate script runs on sample parts (passing, then failing on a planted
change), and its GitHub Actions and GitLab jobs parse and run that script."""

from __future__ import annotations

import json
import os
import re
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from helpers.real_meshes import REPO

DOC = (REPO / "docs" / "ci.md").read_text()
SCRIPT = re.findall(r"```sh\n(.*?)\n```", DOC, re.S)[0]
SCHEMA = Path(__file__).with_name("data") / "junit.xsd"


@pytest.fixture
def checkout(tmp_path):
    """A repository with parts/ (the bundled samples), its baseline, and p3d on PATH."""
    (tmp_path / "parts").mkdir()
    for name in ("bracket.stl", "cube.off", "tetrahedron.stl"):
        shutil.copy(REPO / "sample_meshes" / name, tmp_path / "parts" / name)
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    wrapper = bin_dir / "p3d"
    wrapper.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m p3d_cli "$@"\n')
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IEXEC)
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}",
           "PYTHONPATH": str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", "")}
    baseline = subprocess.run(["p3d", "props", "parts/", "--json"], cwd=tmp_path, env=env,
                              capture_output=True, text=True, check=True)
    (tmp_path / "baseline.ndjson").write_text(baseline.stdout)
    return tmp_path, env


def gate(checkout):
    path, env = checkout
    return subprocess.run(["sh", "-c", SCRIPT], cwd=path, env=env, capture_output=True, text=True, timeout=300)


def test_gate_passes_on_unchanged_clean_parts(checkout):
    done = gate(checkout)
    assert done.returncode == 0, done.stderr
    assert "::" not in done.stdout                     # no annotations when all is well
    lxml = pytest.importorskip("lxml.etree")
    schema = lxml.XMLSchema(lxml.parse(str(SCHEMA)))
    for name in ("p3d-gate.xml",):
        assert schema.validate(lxml.parse(str(checkout[0] / name))), name
    summary = json.loads((checkout[0] / "p3d-summary.json").read_text())
    assert (summary["inputs"], summary["ok"], summary["exit_status"]) == (3, 3, 0)


def test_gate_fails_on_a_planted_change_and_annotates_it(checkout):
    part = checkout[0] / "parts" / "cube.off"
    part.write_text(part.read_text().replace("1 ", "1.001 "))
    done = gate(checkout)
    assert done.returncode == 1, done.stderr
    annotations = [line for line in done.stdout.splitlines() if line.startswith("::error ")]
    assert annotations and all("file=parts/cube.off," in line for line in annotations)
    summary = json.loads((checkout[0] / "p3d-summary.json").read_text())
    assert (summary["failed"], summary["exit_status"]) == (1, 1)


def test_gate_fails_on_a_part_that_is_no_longer_closed(checkout):
    """The one-command gate applies check's requirements (issue 24.6)."""
    part = checkout[0] / "parts" / "cube.off"
    lines = part.read_text().splitlines()
    header = lines[1].split()
    faces = int(header[1])
    lines[1] = f"{header[0]} {faces - 1} {header[2]}"
    part.write_text("\n".join(lines[:-1]) + "\n")          # the last face removed: open
    done = gate(checkout)
    assert done.returncode == 1, done.stderr
    assert any(line.startswith("::error file=parts/cube.off,title=p3d diff [check%3Aclosed]")
               for line in done.stdout.splitlines()), done.stdout


def test_ci_jobs_parse_and_run_the_script():
    blocks = re.findall(r"```yaml\n(.*?)\n```", DOC, re.S)
    github, gitlab = (yaml.safe_load(block) for block in blocks[:2])
    steps = github["jobs"]["p3d"]["steps"]
    assert {"run": "sh ci/meshes.sh"} in steps
    job = gitlab["meshes"]
    assert "sh ci/meshes.sh" in job["script"]
    reports = re.findall(r"junit:(\S+)", SCRIPT)
    assert reports and all(re.fullmatch(job["artifacts"]["reports"]["junit"].replace("*", ".*"), r) for r in reports)


def test_every_warning_code_is_in_the_doc():
    from p3d_cli.warning_codes import CODES

    assert all(f"| `{code}` |" in DOC for code in CODES)
