"""Shell completion by click's environment-variable protocol (the README's recipe): commands
complete, and path arguments complete as file names."""

from __future__ import annotations

import os
import subprocess
import sys


def complete(words: str, shell: str = "bash") -> str:
    env = {**os.environ, "_P3D_COMPLETE": f"{shell}_complete", "COMP_WORDS": words,
           "COMP_CWORD": str(len(words.split()) - (0 if words.endswith(" ") else 1))}
    done = subprocess.run([sys.executable, "-c", "from p3d_cli.cli.main import cli; cli(prog_name='p3d')"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_source_script_is_printed():
    env = {**os.environ, "_P3D_COMPLETE": "bash_source"}
    done = subprocess.run([sys.executable, "-c", "from p3d_cli.cli.main import cli; cli(prog_name='p3d')"],
                          env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0 and "_p3d_completion" in done.stdout and "complete " in done.stdout


def test_commands_and_options_complete():
    assert {"plain,props", "plain,diff"} <= set(complete("p3d ").splitlines()) | set(complete("p3d p").splitlines())
    assert "plain,--ignore-warning" in complete("p3d props --ign").splitlines()


def test_inputs_complete_as_files():
    assert complete("p3d props sam").splitlines() == ["file,sam"]
    assert complete("p3d diff base.ndjson pa").splitlines() == ["file,pa"]
    assert complete("p3d check --files-from li").splitlines() == ["file,li"]
