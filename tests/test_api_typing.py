"""A user's script written against the documented API type-checks with mypy at its default
settings (``tests/typed_user_script.py``), and runs; and mypy does see the types (a script that
misuses them fails), so the check can fail."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from helpers.real_meshes import REPO

SCRIPT = REPO / "tests" / "typed_user_script.py"

# As a user sees an installed package: mypy reports nothing inside it (site-packages are
# silenced), only the user's own code; every other setting is mypy's default. The package is
# found from the source tree (MYPYPATH), as an editable install hides it from mypy.
CONFIG = "[mypy]\n\n[mypy-p3d_cli.*]\nfollow_imports = silent\n"

MISUSE = """import p3d_cli as p3d

result = p3d.props("box:1,2,3")
result.volume.upper()
result.center_of_mass.tolist()
p3d.bounds("box").diagonal.append(1)
p3d.check("part.stl").ok + "yes"
p3d.props("box", densty=1.0)
"""


def mypy(tmp_path, script) -> subprocess.CompletedProcess:
    # The interpreter that runs mypy below must have it (a mypy elsewhere on PATH is not it).
    if subprocess.run([sys.executable, "-c", "import mypy"], capture_output=True).returncode != 0:
        if os.environ.get("CI") == "true":
            pytest.fail("mypy is a test dependency; under CI it must be installed")
        pytest.skip("mypy is not installed")
    (tmp_path / "mypy.ini").write_text(CONFIG)
    env = {**os.environ, "MYPYPATH": str(REPO)}
    return subprocess.run([sys.executable, "-m", "mypy", "--config-file", "mypy.ini", "--no-incremental",
                           "--cache-dir", os.devnull, str(script)], cwd=tmp_path, env=env,
                          capture_output=True, text=True, check=False)


def test_the_users_script_type_checks_at_mypys_defaults(tmp_path):
    done = mypy(tmp_path, SCRIPT)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "Success: no issues found in 1 source file" in done.stdout


def test_the_users_script_runs():
    done = subprocess.run([sys.executable, str(SCRIPT), "sample_meshes/bracket.stl", "no-such-file.stl"], cwd=REPO,
                          capture_output=True, text=True, check=False)
    assert done.returncode == 2, done.stderr     # the missing file is an OSError, caught as such
    assert "cannot read: no-such-file.stl: no such file" in done.stderr
    assert "bracket.stl: 4500 m^3" in done.stdout and "tetrahedron volume 0.16666666666666666" in done.stdout


def test_mypy_sees_the_types_so_misuse_fails(tmp_path):
    script = tmp_path / "misuse.py"
    script.write_text(MISUSE)
    done = mypy(tmp_path, script)
    lines = [line for line in done.stdout.splitlines() if ": error:" in line]
    assert done.returncode == 1 and {int(line.split(":")[1]) for line in lines} == {4, 5, 6, 7, 8}, done.stdout
