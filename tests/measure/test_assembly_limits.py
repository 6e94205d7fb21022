"""Assembly files that expand without bound: a "billion laughs" of files naming the previous one
twice, and chains nested deeper than any recursion should go (docs/assemblies.md, "Limits")."""

from __future__ import annotations

import json

import numpy as np
import pytest

from helpers.cli import run
import p3d_cli as p3d
from p3d_cli.errors import InputError
from p3d_cli.geometry.placement import Placement
from p3d_cli.measure.assembly.parts import MAX_NESTING, MAX_PARTS, Assembly, Part, expanded_parts


def laughs(folder, levels: int) -> str:
    """``a{levels}.yaml``: each file names the one before it twice (2**levels boxes)."""
    (folder / "a0.yaml").write_text("parts:\n  - shape: box:1,1,1\n")
    for i in range(1, levels + 1):
        (folder / f"a{i}.yaml").write_text(f"parts:\n  - assembly: a{i - 1}.yaml\n"
                                           f"  - assembly: a{i - 1}.yaml\n    translate: [{2 ** i}, 0, 0]\n")
    return str(folder / f"a{levels}.yaml")


def chain(folder, levels: int) -> str:
    """``d{levels}.yaml``: each file holds the one before it, moved by 1 along x."""
    (folder / "d0.yaml").write_text("parts:\n  - shape: box:1,1,1\n")
    for i in range(1, levels + 1):
        (folder / f"d{i}.yaml").write_text(f"parts:\n  - assembly: d{i - 1}.yaml\n    translate: [1, 0, 0]\n")
    return str(folder / f"d{levels}.yaml")


def test_a_billion_laughs_of_assembly_files_is_refused_before_any_part_is_measured(tmp_path):
    path = laughs(tmp_path, 40)                                   # 2**40 parts from 41 small files
    result = run("props", "--json", path)
    assert result.exit_code == 2
    assert "expands to 1,099,511,627,776 parts" in result.stderr
    assert f"limit of {MAX_PARTS:,}" in result.stderr
    assert result.stderr.count("\n") == 1 and result.stderr.startswith("p3d: error: ")
    assert "error" in json.loads(result.stdout)
    assert run("bounds", path).exit_code == 2


def test_repeated_files_are_read_once_and_measured_as_often_as_included(tmp_path):
    path = laughs(tmp_path, 6)                                    # 64 boxes side by side
    assert expanded_parts(p3d.load_assembly(path)) == 64
    result = p3d.props(path)
    assert result.properties.volume == 64 * 8.0
    assert len(result.parts) == 64


def test_nesting_deeper_than_the_limit_is_one_clear_error(tmp_path):
    path = chain(tmp_path, 3 * MAX_NESTING)
    result = run("props", path)
    assert result.exit_code == 2
    assert f"more than {MAX_NESTING}" in result.stderr and "Traceback" not in result.output
    assert result.stderr.count("\n") == 1


def test_nesting_up_to_the_limit_is_measured(tmp_path):
    path = chain(tmp_path, MAX_NESTING - 1)
    result = p3d.props(path)
    assert result.properties.volume == 8.0
    assert result.properties.center_of_mass.tolist() == [MAX_NESTING - 1, 0.0, 0.0]


def test_the_limits_hold_for_assemblies_built_in_python():
    box = Part("box", "box:1,1,1")
    nested = Assembly("a0", (box,))
    for i in range(MAX_NESTING + 1):
        nested = Assembly(f"a{i + 1}", (Part("in", nested, Placement(translation=np.ones(3))),))
    with pytest.raises(InputError, match="levels deep"):
        p3d.props(nested)
    wide = Assembly("w0", (box, box))
    for i in range(20):                                            # 2**21 parts, 21 objects
        wide = Assembly(f"w{i + 1}", (Part("l", wide), Part("r", wide)))
    with pytest.raises(InputError, match="expands to 2,097,152 parts"):
        p3d.props(wide)
