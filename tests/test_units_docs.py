"""docs/units.md and docs/assemblies.md cannot drift: their `$ p3d ...` examples run as shown
(the assembly file of docs/assemblies.md is written from its YAML block first)."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO

DOCS = {name: (REPO / "docs" / name).read_text() for name in ("units.md", "assemblies.md")}


def examples():
    out = []
    for name, doc in DOCS.items():
        lines = doc.splitlines()
        for i, line in enumerate(lines):
            if line.startswith("    $ p3d "):
                expected = []
                for follow in lines[i + 1:]:
                    if not follow.startswith("    ") or follow.startswith("    $ "):
                        break
                    expected.append(follow[4:])
                out.append((name, line[6:], expected))
    return out


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"-?\d+\.?\d*(?:e-?\d+)?", text)]


@pytest.mark.parametrize("doc, line, expected", examples(), ids=lambda v: v if isinstance(v, str) else "")
def test_examples_run_as_shown(tmp_path, doc, line, expected):
    yaml_block = re.search(r"```yaml\n(.*?)```", DOCS["assemblies.md"], re.S).group(1)
    (tmp_path / "link.yaml").write_text(yaml_block)
    words = shlex.split(line)
    done = subprocess.run([sys.executable, "-m", "p3d_cli", *words[1:]], cwd=tmp_path,
                          capture_output=True, text=True, check=False)
    shown = (done.stdout + done.stderr).strip()
    want = "\n".join(expected).strip()
    if want.startswith("p3d: error:"):
        assert done.returncode == 2 and shown == want
        return
    assert done.returncode == 0, done.stderr
    assert re.sub(r"[-\d.e]+", "#", shown) == re.sub(r"[-\d.e]+", "#", want)
    np.testing.assert_allclose(numbers(shown), numbers(want), rtol=1e-12, atol=1e-15)


def test_python_example_runs():
    code = re.search(r"```python\n(.*?)```", DOCS["units.md"], re.S).group(1)
    scope: dict = {}
    exec(code, scope)                      # noqa: S102 - the document's own example
    assert scope["r"].units["mass"] == "kg"
    assert len(examples()) >= 5
