"""Fixtures of the repair tests: the cube, and the exact tests of the self-intersection work
(weld, nesting) replaced by slow oracles where this build lacks them."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import CUBE_FACES, CUBE_VERTICES
from helpers.repair_oracles import box_nesting, brute_weld
from p3d_cli.repairs import solidity


@pytest.fixture
def cube() -> np.ndarray:
    """The unit cube [0, 1]^3, 12 faces wound outward, float64."""
    return CUBE_VERTICES[CUBE_FACES].copy()


@pytest.fixture
def oracles(monkeypatch):
    """Weld and nesting by the brute-force oracles when the build lacks the exact ones (the
    steps' logic is what these tests are about; the exact tests have their own)."""
    if not solidity.available("p3d_cli.mesh.weld"):
        monkeypatch.setattr(solidity, "weld_points", brute_weld)
    if not solidity.available("p3d_cli.mesh.nesting"):
        monkeypatch.setattr(solidity, "nesting_depths", box_nesting)
