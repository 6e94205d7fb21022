"""The repository's folder, the shared real meshes beside it, and their exact references."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
REAL_MESHES = REPO.parent / "shared" / "real-meshes"


def real_meshes_dir() -> Path:
    """The shared real meshes; skip when absent, except under CI where they must be there."""
    if (REAL_MESHES / "reference.json").is_file():
        return REAL_MESHES
    if os.environ.get("CI") == "true":
        pytest.fail(f"CI=true but the real meshes are missing at {REAL_MESHES}")
    pytest.skip(f"real meshes not found at {REAL_MESHES}")


def check_reference(props, ref: dict) -> None:
    """Mass properties against one entry of the real meshes' reference.json, to 1e-12 (volume
    relative, centre relative to the bounding diagonal, inertia in the Frobenius norm).

    An inward-wound reference (negative volume) is compared flipped: p3d measures the solid
    such a mesh encloses, every signed integral changing sign (issue 12.6)."""
    sign = -1.0 if ref["volume"] < 0 else 1.0
    assert abs(props.volume - sign * ref["volume"]) <= 1e-12 * abs(ref["volume"])
    diagonal = np.linalg.norm(np.subtract(ref["bounds_max"], ref["bounds_min"]))
    assert np.linalg.norm(props.center_of_mass - ref["center_mass"]) <= 1e-12 * diagonal
    inertia = sign * np.array(ref["inertia_com"])
    assert np.linalg.norm(props.inertia - inertia) <= 1e-12 * np.linalg.norm(inertia)
