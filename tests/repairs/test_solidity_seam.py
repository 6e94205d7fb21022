"""The seam to the exact solidity tests (``p3d_cli.repairs.solidity``): with a test missing
from the build, each step that needs it says so and changes nothing it cannot vouch for."""

from __future__ import annotations

import numpy as np
import pytest

from p3d_cli.repairs import repair, solidity


@pytest.fixture
def without_solidity(monkeypatch):
    """Every exact test but the orientation signs reported missing."""
    real = solidity._module

    def module(name):
        if name == "p3d_cli.geometry.predicates":
            return real(name)
        raise solidity.Unavailable(name)

    monkeypatch.setattr(solidity, "_module", module)


def test_weld_without_the_weld_test_is_not_done(cube, without_solidity):
    broken = cube.copy()
    broken[0, 0] += [1e-9, 0, 0]
    _, report = repair(broken, weld=1e-6)
    weld = report.step("weld")
    assert not weld.ran and "lacks the weld" in weld.notes[0]
    assert not report.fixed


def test_several_closed_shells_without_nesting_are_left_as_they_were(cube, without_solidity):
    inward_apart = np.concatenate([cube, cube[:, [0, 2, 1]] + 3.0])
    mesh, report = repair(inward_apart)
    outward = report.step("outward")
    assert not outward.ran and "exact nesting test" in outward.notes[-1]
    assert not report.changed and mesh.triangles.tobytes() == inward_apart.tobytes()


def test_filled_holes_say_they_were_not_tested_for_crossings(cube, without_solidity):
    _, report = repair(cube[2:])
    assert report.fixed
    assert "not tested for crossing" in report.step("holes").notes[-1]


def test_with_the_oracles_the_same_meshes_are_fixed(cube, oracles):
    inward_apart = np.concatenate([cube, cube[:, [0, 2, 1]] + 3.0])
    _, report = repair(inward_apart)
    assert report.fixed and report.step("outward").counts["shells_flipped"] == 1
