"""The documents' indented `$ p3d ...` examples, run as shown (one runner for every doc test).

An example is a line ``    $ p3d ARGS`` followed by the indented lines it prints. Output is
compared as text with every number masked, then number by number within a tolerance, so
that the documents cannot drift while the last digits may move with the platform.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np

NUMBER = r"-?\d+\.?\d*(?:e[-+]?\d+)?"


def examples(text: str) -> list[tuple[str, str]]:
    """``(command line, printed text)`` of each indented ``$ p3d`` example in ``text``."""
    lines = text.splitlines()
    out = []
    for i, line in enumerate(lines):
        if line.startswith("    $ p3d "):
            shown = []
            for follow in lines[i + 1:]:
                if not follow.startswith("    ") or follow.startswith("    $ "):
                    break
                shown.append(follow[4:])
            out.append((line[6:], "\n".join(shown).strip()))
    return out


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(NUMBER, text)]


def run(line: str, cwd: Path) -> tuple[int, str]:
    """Exit status and printed text (stdout then stderr) of ``p3d ...`` run in ``cwd``."""
    done = subprocess.run([sys.executable, "-m", "p3d_cli", *shlex.split(line)[1:]], cwd=cwd,
                          capture_output=True, text=True, check=False)
    return done.returncode, (done.stdout + done.stderr).strip()


def assert_as_shown(line: str, shown: str, cwd: Path, *, status: int | None = None,
                    rtol: float = 1e-12, atol: float = 1e-15) -> None:
    """Run the example and check its status (2 for a shown error, else ``status`` or 0) and
    its text and numbers against ``shown``."""
    code, printed = run(line, cwd)
    if shown.startswith("p3d: error:"):
        assert code == 2 and printed == shown, printed
        return
    assert code == (0 if status is None else status), printed
    assert re.sub(NUMBER, "#", printed) == re.sub(NUMBER, "#", shown)
    np.testing.assert_allclose(numbers(printed), numbers(shown), rtol=rtol, atol=atol)
