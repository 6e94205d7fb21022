"""Shared test set-up: hypothesis profiles, the real-mesh folder, small mesh builders."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

# Bounded example counts keep the suite within a few minutes on two cores. "ci" is the
# default, and derandomised: the same examples on every run, so a CI verdict depends on the code,
# not on the draw (and no example database is read or written). "dev" and "thorough" draw anew
# each run and keep their database: use them to look for new failures by hand.
settings.register_profile("ci", max_examples=30, deadline=None, print_blob=True, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", max_examples=60, deadline=None)
settings.register_profile("thorough", max_examples=1000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))

# Every --json record a test makes is validated against the package's schema of its kind.
pytest_plugins = ["helpers.record_schemas"]

REPO = Path(__file__).resolve().parents[1]
REAL_MESHES = REPO.parent / "shared" / "real-meshes"


def real_meshes_dir() -> Path:
    """The shared real meshes; skip when absent, except under CI where they must be there."""
    if (REAL_MESHES / "reference.json").is_file():
        return REAL_MESHES
    if os.environ.get("CI") == "true":
        pytest.fail(f"CI=true but the real meshes are missing at {REAL_MESHES}")
    pytest.skip(f"real meshes not found at {REAL_MESHES}")


@pytest.fixture(scope="session")
def real_meshes() -> Path:
    return real_meshes_dir()


@pytest.fixture(scope="session")
def reference(real_meshes) -> dict:
    """reference.json as a dict keyed by file name."""
    entries = json.loads((real_meshes / "reference.json").read_text())
    return {entry["file"]: entry for entry in entries}


CUBE_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                          [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
CUBE_FACES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                       [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


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


def cube_triangles() -> np.ndarray:
    """The unit cube [0, 1]³ as 12 outward-wound triangles, (12, 3, 3) float64."""
    return CUBE_VERTICES[CUBE_FACES]


def write_binary_stl(path, triangles: np.ndarray, header: bytes = b"p3d test") -> None:
    """Write ``triangles`` (n, 3, 3) as binary STL (float32, zero normals)."""
    triangles = np.asarray(triangles, dtype=np.float32)
    records = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = triangles
    with open(path, "wb") as f:
        f.write(header[:80].ljust(80, b" "))
        f.write(np.uint32(len(triangles)).tobytes())
        f.write(records.tobytes())


def write_ascii_stl(path, triangles: np.ndarray, name: str = "part") -> None:
    """Write ``triangles`` as ASCII STL with full float64 precision (repr)."""
    lines = [f"solid {name}"]
    for tri in np.asarray(triangles, dtype=np.float64):
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in tri.tolist()]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}")
    Path(path).write_text("\n".join(lines) + "\n")
