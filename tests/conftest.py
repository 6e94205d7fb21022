"""Shared test set-up: hypothesis profiles, the record-schema plugin and the fixtures.

Fixtures only: the plain functions and constants tests share live in the ``helpers`` package
(``helpers.meshes``, ``helpers.real_meshes``, ``helpers.cli``); tests never import conftest."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from helpers.real_meshes import real_meshes_dir

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


@pytest.fixture(scope="session")
def real_meshes() -> Path:
    return real_meshes_dir()


@pytest.fixture(scope="session")
def reference(real_meshes) -> dict:
    """reference.json as a dict keyed by file name."""
    entries = json.loads((real_meshes / "reference.json").read_text())
    return {entry["file"]: entry for entry in entries}
