"""The arm fixture: the two-link arm of ``helpers.robot_arm`` written into the test's folder."""

from __future__ import annotations

import pytest

from helpers.robot_arm import Arm


@pytest.fixture
def arm(tmp_path) -> Arm:
    return Arm(tmp_path)
