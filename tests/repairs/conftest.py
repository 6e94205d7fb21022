"""Fixtures of the repair tests: the unit cube."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import CUBE_FACES, CUBE_VERTICES


@pytest.fixture
def cube() -> np.ndarray:
    """The unit cube [0, 1]^3, 12 faces wound outward, float64."""
    return CUBE_VERTICES[CUBE_FACES].copy()
