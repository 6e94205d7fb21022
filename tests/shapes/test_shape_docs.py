"""docs/shapes.md cannot drift: its `$ p3d ...` examples and its tessellation table are checked."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO

DOC = (REPO / "docs" / "shapes.md").read_text()


def examples():
    """(command line, expected output lines) for each indented `$ p3d` example."""
    out = []
    lines = DOC.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("    $ p3d "):
            expected = []
            for follow in lines[i + 1:]:
                if not follow.startswith("    ") or follow.startswith("    $ "):
                    break
                expected.append(follow[4:])
            out.append((line[6:], expected))
    return out


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"-?\d+\.?\d*(?:e-?\d+)?", text)]


@pytest.mark.parametrize("line, expected", examples(), ids=lambda v: v if isinstance(v, str) else "")
def test_examples_run_as_shown(line, expected):
    words = shlex.split(line)
    done = subprocess.run([sys.executable, "-m", "p3d_cli", *words[1:]], cwd=REPO,
                          capture_output=True, text=True, check=False)
    shown = (done.stdout + done.stderr).strip()
    want = "\n".join(expected).strip()
    if want.startswith("p3d: error:"):
        assert done.returncode == 2 and shown == want
        return
    assert done.returncode == 0, done.stderr
    assert re.sub(r"[-\d.e]+", "#", shown) == re.sub(r"[-\d.e]+", "#", want)
    np.testing.assert_allclose(numbers(shown), numbers(want), rtol=1e-12, atol=1e-12)


def test_there_are_examples():
    assert len(examples()) >= 4


def test_tessellation_table_is_the_scripts_output():
    sys.path.insert(0, str(REPO / "benchmarks"))
    from tessellation_error import errors
    from p3d_cli.shapes import Cylinder, Sphere

    rows = re.findall(r"^\| (sphere|cylinder) \| (\d+) \| (\d+) \| (\S+) \| (\S+) \| (\S+) \|$", DOC, re.M)
    assert len(rows) >= 12
    for label, n, count, ev, _, ei in rows:
        if int(n) > 256:
            continue                     # the finest rows take seconds; the trend is checked below
        shape = Sphere(1.0) if label == "sphere" else Cylinder(1.0, 1.0)
        got = errors(shape, int(n))
        assert got[0] == int(count)
        assert got[1] == pytest.approx(float(ev), rel=1e-3)
        assert got[2] == pytest.approx(float(ei), rel=1e-3)
    for label in ("sphere", "cylinder"):
        scaled = [float(r[4]) for r in rows if r[0] == label]
        assert abs(scaled[-1] - scaled[-2]) < 1e-3 * abs(scaled[-1])       # error × N² settles
