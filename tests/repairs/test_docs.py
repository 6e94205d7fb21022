"""docs/repair.md cannot drift: its examples run as shown, on the boxes it describes."""

from __future__ import annotations

import os
import re

import numpy as np
import pytest

from helpers.meshes import CUBE_FACES, CUBE_VERTICES, write_binary_stl
from helpers.real_meshes import REPO
from helpers.doc_examples import assert_as_shown, examples

DOC = (REPO / "docs" / "repair.md").read_text()
BOX = CUBE_VERTICES[CUBE_FACES] * 10.0


def boxes(folder) -> None:
    """The files the document names: a 10 x 10 x 10 box without its top, one with a hole bent
    across an edge, and the part of the Python example (the open box again)."""
    write_binary_stl(folder / "box-open.stl", np.delete(BOX, [2, 3], axis=0))
    write_binary_stl(folder / "box-bent.stl", np.delete(BOX, [0, 4], axis=0))
    write_binary_stl(folder / "part.stl", np.delete(BOX, [2, 3], axis=0))


@pytest.mark.parametrize("line, shown", examples(DOC), ids=lambda v: v if v.startswith("p3d") else "")
def test_examples_run_as_shown(tmp_path, line, shown):
    boxes(tmp_path)
    assert_as_shown(line, shown, tmp_path, status=1 if "NOT FIXED" in shown else 0)


def test_python_example_runs(tmp_path, monkeypatch):
    boxes(tmp_path)
    monkeypatch.chdir(tmp_path)
    code = re.search(r"```python\n(.*?)```", DOC, re.S).group(1)
    scope: dict = {}
    exec(code, scope)                      # noqa: S102 - the document's own example
    assert scope["report"].fixed and os.path.exists("fixed.stl") is False   # over the 1e-6 limit: refused
    assert len(examples(DOC)) >= 2
