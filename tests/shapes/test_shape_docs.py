"""docs/shapes.md cannot drift: its `$ p3d ...` examples and its tessellation table are checked."""

from __future__ import annotations

import re
import sys

import pytest

from helpers.real_meshes import REPO
from helpers.doc_examples import assert_as_shown, examples

DOC = (REPO / "docs" / "shapes.md").read_text()


@pytest.mark.parametrize("line, shown", examples(DOC), ids=lambda v: v if isinstance(v, str) else "")
def test_examples_run_as_shown(line, shown):
    assert_as_shown(line, shown, REPO, atol=1e-12)


def test_there_are_examples():
    assert len(examples(DOC)) >= 4


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
