"""The README cannot drift: its set-up commands and every `$ p3d ...` example are checked."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

from conftest import REPO

README = (REPO / "README.md").read_text()


def test_readme_opens_with_the_two_setup_commands():
    blocks = re.findall(r"```sh\n(.*?)\n```", README, re.S)
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
