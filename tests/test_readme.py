"""The README cannot drift: its set-up commands and every `$ p3d ...` example are checked."""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from helpers.real_meshes import REPO

README = (REPO / "README.md").read_text()


def test_readme_opens_with_the_two_setup_commands():
    blocks = _readme_blocks()
    assert blocks[0].startswith("python3 -m venv") and "pip install . && p3d props sample_meshes/" in blocks[0]
    assert "pip install '.[test]' && pytest" in blocks[1]
    sample = blocks[0].rsplit("p3d props ", 1)[1].split()[0]
    assert (REPO / sample).is_file()


def test_readme_examples_run():
    examples = re.findall(r"^\$ (p3d .*)$", README, re.M)
    assert len(examples) >= 5
    for line in examples:
        words = shlex.split(line.split("<")[0])
        stdin = None
        if "<" in line:
            stdin = open(REPO / line.split("<")[1].strip(), "rb")
        done = subprocess.run([sys.executable, "-m", "p3d_cli", *words[1:]], cwd=REPO, stdin=stdin,
                              capture_output=True, text=True, check=False)
        assert done.returncode == 0, f"{line}\n{done.stderr}"
        assert done.stdout.strip(), line


def test_readme_python_example_runs():
    blocks = re.findall(r"```python\n(.*?)\n```", README, re.S)
    assert blocks, "the README shows the Python API"
    for code in blocks:
        done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=False)
        assert done.returncode == 0, f"{code}\n{done.stderr}"
        assert "both given; they are exclusive" in done.stdout and "--" not in done.stdout


def test_api_doc_examples_run():
    text = (REPO / "docs" / "api.md").read_text()
    blocks = re.findall(r"```python\n(.*?)\n```", text, re.S)
    assert len(blocks) >= 4
    code = "\n".join(blocks)  # later examples use names the first ones define, as a reader would
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert "sample_meshes/bracket.stl" in done.stdout


def _readme_blocks() -> list[str]:
    return re.findall(r"```sh\n(.*?)\n```", README, re.S)


def test_bare_pytest_collects_without_errors():
    """The README runs bare ``pytest``, which (unlike ``python -m pytest``) does not put the working
    directory on the import path: every test module must import that way too."""
    pytest_script = Path(sys.executable).with_name("pytest")
    if not pytest_script.is_file():
        pytest.skip(f"no pytest console script beside {sys.executable}")
    env = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    done = subprocess.run([str(pytest_script), "--collect-only", "-q", "-p", "no:cacheprovider"], cwd=REPO,
                          env=env, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert "error" not in done.stdout.splitlines()[-1].lower(), done.stdout[-3000:]
    assert re.search(r"\b[1-9][0-9]{2,} tests collected\b", done.stdout), done.stdout[-500:]


def test_ci_runs_the_readme_test_command_as_written():
    """.ci/run takes the command from the README (the second sh block), not a copy of it."""
    done = subprocess.run(["bash", str(REPO / ".ci" / "run"), "--print-command"], cwd=REPO,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert done.stdout.rstrip("\n") == _readme_blocks()[1]


def test_docs_name_only_install_lines_that_work():
    """p3d is not on PyPI (issue 24.4): no `pip install p3d-cli`, no `p3d-cli[extra]` to install, and
    every extra named in an install line is one pyproject declares."""
    try:
        import tomllib
    except ImportError:      # Python 3.10
        import tomli as tomllib
    extras = set(tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["optional-dependencies"])
    pages = [REPO / "README.md", REPO / "CHANGELOG.md", *sorted((REPO / "docs").glob("*.md"))]
    for page in pages:
        for number, line in enumerate(page.read_text().splitlines(), 1):
            for command in re.findall(r"pip install [^`\n]*", line):
                assert "p3d-cli" not in command, f"{page.name}:{number}: {command}"
                for named in re.findall(r"'\.\[([a-z,]+)\]'", command):
                    assert set(named.split(",")) <= extras, f"{page.name}:{number}: {command}"
    assert "p3d is not on PyPI" in " ".join(README.split())
