"""Mangled descriptions give one p3d error or a result, never another exception or a hang."""

from __future__ import annotations

import os
import re

import pytest

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from p3d_cli.errors import P3DError
from p3d_cli.robots import check_robot, fill_robot, load_robot

WORDS = st.sampled_from(["0", "-1", "1e308", "nan", "", "x", "0 0", "1 1 1 1", "-0.001 0.001 0.001", "1e-320"])


@pytest.mark.filterwarnings("error::RuntimeWarning")
@settings(max_examples=int(os.environ.get("P3D_ROBOT_EXAMPLES", 60)), deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data(), kind=st.sampled_from(["urdf", "mjcf", "sdf"]))
def test_mangled_numbers(arm, data, kind):
    path = {"urdf": arm.urdf, "mjcf": arm.mjcf, "sdf": arm.sdf}[kind]("mangled." + kind)
    text = path.read_text()
    spots = [m.span() for m in re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text)]
    for _ in range(data.draw(st.integers(1, 3))):
        start, end = data.draw(st.sampled_from(spots))
        text = text[:start] + data.draw(WORDS) + text[end:]
        spots = [m.span() for m in re.finditer(r"-?\d+(\.\d+)?(e-?\d+)?", text)]
    path.write_text(text)
    try:
        robot = load_robot(path, {**arm.packages})
        checks = check_robot(robot)
        filled = fill_robot(robot, density=1000.0, force=True)
    except P3DError as error:
        # One p3d error, saying where (the file) and what: never another exception.
        assert "mangled" in error.where and error.what
        return
    assert {c.link for c in checks} == {link.name for link in robot.links}
    assert filled.data.startswith(b"<")
