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


# Issue #27's hostile cases: each was an internal error (exit 3) or a hang.

def test_capsule_from_fromto_without_size_is_one_error(tmp_path):
    from p3d_cli.errors import InputError

    path = tmp_path / "capsule.xml"
    path.write_text('<mujoco><worldbody><body name="a"><geom type="capsule" fromto="0 0 0 0 0 1"/></body>'
                    '</worldbody></mujoco>')
    with pytest.raises(InputError, match=r"body 'a'.*capsule given by fromto needs its radius in size"):
        load_robot(path)


def _chain_mjcf(depth: int, geoms: int = 0) -> str:
    """A rope of ``depth`` nested bodies; the first ``geoms`` have a capsule (the walk is what
    was recursive: the others keep the test fast)."""
    bodies = "".join(f'<body name="b{i}" pos="0 0 0.1"><joint type="hinge"/>' + (
        '<geom type="capsule" fromto="0 0 0 0 0 0.1" size="0.01"/>' if i < geoms else "") for i in range(depth))
    return f"<mujoco><worldbody>{bodies}{'</body>' * depth}</worldbody></mujoco>"


def test_a_1000_body_mjcf_chain_reads_checks_and_fills(tmp_path):
    """A saved rope: 1,000 nested bodies once exhausted the recursion (exit 3)."""
    path = tmp_path / "rope.xml"
    path.write_text(_chain_mjcf(1000, geoms=3))
    robot = load_robot(path)
    assert [link.name for link in robot.links] == [f"b{i}" for i in range(1000)]
    assert len(check_robot(robot)) == 1000
    result = fill_robot(robot)
    assert [link.status for link in result.links[:4]] == ["filled"] * 3 + ["kept"]


def test_mujoco_agrees_on_a_chain():
    # MuJoCo's XML parser (tinyxml2) stops at 500 levels of nesting: its bodies, in its order.
    mujoco = pytest.importorskip("mujoco")
    text = _chain_mjcf(400, geoms=400)
    model = mujoco.MjModel.from_xml_string(text)
    assert [model.body(i).name for i in range(1, model.nbody)] == [f"b{i}" for i in range(400)]


def test_3000_deep_urdfs_read(tmp_path):
    """3,000 links in a chain, and 3,000 elements nested in an extension block."""
    links = "".join(f'<link name="l{i}"/>' + (f'<joint name="j{i}" type="fixed"><parent link="l{i - 1}"/><child link="l{i}"/></joint>'
                       if i else "") for i in range(3000))
    nested = "<gazebo>" + "<plugin>" * 3000 + "</plugin>" * 3000 + "</gazebo>"
    path = tmp_path / "deep.urdf"
    path.write_text(f'<robot name="deep">{links}{nested}</robot>')
    robot = load_robot(path)
    assert len(robot.links) == 3000
    assert len(check_robot(robot)) == len(fill_robot(robot, density=1000.0).links) == 3000
    deep = tmp_path / "deep-mjcf.xml"
    deep.write_text("<mujoco><default>" + '<default class="c">' * 0 + "".join(f'<default class="c{i}">'
                    for i in range(3000)) + "</default>" * 3001 + "<worldbody/></mujoco>")
    assert load_robot(deep).links == []


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs here")
def test_no_read_of_a_fifo_beside_the_model(tmp_path, arm):
    """A FIFO named as a mesh, an include or the description itself is refused, not read
    (a read would block forever)."""
    import threading

    from p3d_cli.errors import InputError

    os.mkfifo(tmp_path / "pipe.stl")
    os.mkfifo(tmp_path / "pipe.xml")
    cases = {
        "mesh.urdf": '<robot name="r"><link name="a"><collision><geometry><mesh filename="pipe.stl"/></geometry>'
                     "</collision></link></robot>",
        "mesh.xml": '<mujoco><asset><mesh file="pipe.stl"/></asset><worldbody><body name="a"><geom type="mesh" '
                    'mesh="pipe"/></body></worldbody></mujoco>',
        "include.xml": '<mujoco><include file="pipe.xml"/></mujoco>',
    }
    outcome: dict[str, str] = {}

    def run():
        for name, text in cases.items():
            (tmp_path / name).write_text(text)
            try:
                load_robot(tmp_path / name)
                outcome[name] = "read"
            except InputError as error:
                outcome[name] = error.what
        try:
            load_robot(tmp_path / "pipe.xml")
        except InputError as error:
            outcome["pipe.xml"] = error.what

    worker = threading.Thread(target=run, daemon=True)
    worker.start()
    worker.join(20)
    assert not worker.is_alive(), "blocked on a FIFO"
    assert len(outcome) == 4 and all("not a regular file" in what for what in outcome.values()), outcome
