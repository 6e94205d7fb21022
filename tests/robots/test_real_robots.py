"""The real descriptions of ``../shared/real-robots/`` (its README lists each construct and where it
occurs): every one loads, checks and fills; each filled description loads in the tools users
run (yourdfpy and pinocchio for URDF, MuJoCo for MJCF; SDF is read back by lxml and by p3d)
with p3d's numbers to 1e-9, and a byte diff shows only the inertial elements changed.

The folders are read by path and copied to the test's temporary folder before a fill (they
are read-only, and MJCF meshes resolve relative to the model). Skipped when absent, except
under CI (``CI=true``), where a missing folder fails.
"""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from p3d_cli.robots import check_robot, fill_robot, load_robot
from p3d_cli.robots.fill import write_fill

REAL = Path(__file__).resolve().parents[2].parent / "shared" / "real-robots"
INERTIAL = re.compile(r"\s*<inertial\b(?:[^>]*/>|.*?</inertial\s*>)", re.S)


def folder(name: str) -> Path:
    path = REAL / name
    if not path.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"{path} is missing (CI has every real file)")
        pytest.skip(f"{path} is absent")
    return path


#: name -> (description, package map relative to the folder, the links the README counts)
CASES = {
    "kuka": ("kuka_kr16_2", "kuka_kr16_support/urdf/kr16_2.urdf", {"kuka_kr16_support": "kuka_kr16_support"}, 9),
    "kuka-xacro": ("kuka_kr16_2", "kuka_kr16_support/urdf/kr16_2.xacro", {"kuka_kr16_support": "kuka_kr16_support"},
                   10),
    "open_manipulator": ("open_manipulator_x",
                         "open_manipulator_description/urdf/open_manipulator_x/open_manipulator_x.urdf.xacro",
                         {"open_manipulator_description": "open_manipulator_description",
                          "open_manipulator_bringup": "."}, 9),
    "prius": ("prius", "prius_description/urdf/prius.urdf", {"prius_description": "prius_description"}, 28),
    "vx300s": ("menagerie_vx300s", "trossen_vx300s/scene.xml", {}, 10),
    "shadow_hand": ("menagerie_shadow_hand_2022", "shadow_hand/right_hand.xml", {}, 30),
    "fetch": ("gym_fetch", "gymnasium_robotics/envs/assets/fetch/reach.xml", {}, 31),
    "replicate": ("mujoco_replicate", "model/replicate/bunnies.xml", {}, 126),
    "omniquad": ("px4_models", "models/omniquad/model.sdf", {"omniquad_base": "models/omniquad_base"}, 9),
    "rover": ("px4_models", "models/rover_differential/model.sdf",
              {"rover_differential": "models/rover_differential"}, 5),
}


def _copy(case: str, tmp_path: Path):
    name, file, packages, count = CASES[case]
    root = tmp_path / name
    shutil.copytree(folder(name), root)
    for path in root.rglob("*"):  # the copies keep the read-only modes of the originals
        os.chmod(path, 0o755 if path.is_dir() else 0o644)
    return root / file, {k: str(root / v) for k, v in packages.items()}, count


@pytest.mark.parametrize("case", sorted(CASES))
def test_every_real_description_loads_and_checks(case):
    name, file, packages, count = CASES[case]
    root = folder(name)
    if file.endswith(".xacro"):
        pytest.importorskip("xacro")
    robot = load_robot(root / file, {k: str(root / v) for k, v in packages.items()})
    assert len(robot.links) == count
    for role in ("collision", "visual"):
        checks = check_robot(robot, role=role)
        assert [c.link for c in checks] == [link.name for link in robot.links]


def test_gazebo_links_are_not_robot_links():
    robot = load_robot(folder("prius") / "prius_description/urdf/prius.urdf",
                       {"prius_description": str(folder("prius") / "prius_description")})
    assert len(robot.links) == 28 and all("gazebo" not in link.node.parent.tag for link in robot.links)


def test_replicate_gives_mujocos_bodies():
    mujoco = pytest.importorskip("mujoco")
    path = folder("mujoco_replicate") / "model/replicate/bunnies.xml"
    model = mujoco.MjModel.from_xml_path(str(path))
    robot = load_robot(path)
    assert len(robot.links) == model.nbody - 1 == 126


def _changed_only_inertials(before: bytes, after: bytes) -> None:
    assert after != before
    assert INERTIAL.sub("", before.decode()) == INERTIAL.sub("", after.decode())


def _fill(case, tmp_path, **options):
    path, packages, _ = _copy(case, tmp_path)
    robot = load_robot(path, packages)
    result = fill_robot(robot, **{"mass_from": "declared", "density": 1000.0, "force": True, **options})
    originals = {p: Path(p).read_bytes() for p in result.files if os.path.exists(p)}
    return path, packages, robot, result, originals


@pytest.mark.parametrize("case", ["kuka", "prius"])
def test_filled_real_urdf_loads_in_yourdfpy_and_pinocchio(case, tmp_path):
    yourdfpy = pytest.importorskip("yourdfpy")
    pin = pytest.importorskip("pinocchio")
    path, packages, robot, result, originals = _fill(case, tmp_path)
    write_fill(robot, result)
    for file, before in originals.items():
        _changed_only_inertials(before, Path(file).read_bytes())
    filled = {f.link: f for f in result.links if f.status == "filled"}
    assert filled
    model = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
    for name, f in filled.items():
        inertial = model.link_map[name].inertial
        r = inertial.origin[:3, :3]
        assert inertial.mass == pytest.approx(f.mass, rel=1e-12)
        np.testing.assert_allclose(inertial.origin[:3, 3], f.center, rtol=0, atol=1e-12)
        np.testing.assert_allclose(r @ inertial.inertia @ r.T, f.inertia, rtol=0, atol=1e-9 * np.abs(f.inertia).max())
    pinocchio_model = pin.buildModelFromUrdf(str(path))
    # Pinocchio keeps a link's inertia with the joint that moves it (in that joint's frame, the
    # link's own when the frame sits at the joint); links on fixed joints are merged into it.
    frames = {f.name: f for f in pinocchio_model.frames if f.type == pin.FrameType.BODY}
    per_joint: dict[int, list[str]] = {}
    for link in load_robot(path, packages).links:
        if link.inertial is not None and link.inertial.mass > 0:
            per_joint.setdefault(frames[link.name].parentJoint, []).append(link.name)
    compared = 0
    for name, f in filled.items():
        frame = frames[name]
        if per_joint.get(frame.parentJoint) != [name] or not frame.placement.isIdentity() or frame.parentJoint == 0:
            continue
        inertia = pinocchio_model.inertias[frame.parentJoint]
        assert inertia.mass == pytest.approx(f.mass, rel=1e-12)
        np.testing.assert_allclose(inertia.lever, f.center, rtol=0, atol=1e-12)
        np.testing.assert_allclose(inertia.inertia, f.inertia, rtol=0, atol=1e-9 * np.abs(f.inertia).max())
        compared += 1
    assert compared >= 1


def test_filled_xacro_writes_a_urdf_that_loads(tmp_path):
    pytest.importorskip("xacro")
    yourdfpy = pytest.importorskip("yourdfpy")
    path, packages, robot, result, _ = _fill("open_manipulator", tmp_path)
    out = tmp_path / "filled.urdf"
    write_fill(robot, result, out)
    model = yourdfpy.URDF.load(str(out), build_scene_graph=False, load_meshes=False)
    for f in result.links:
        if f.status == "filled":
            assert model.link_map[f.link].inertial.mass == pytest.approx(f.mass, rel=1e-12)


@pytest.mark.parametrize("case", ["vx300s", "shadow_hand", "fetch", "replicate"])
def test_filled_real_mjcf_compiles_in_mujoco_with_p3ds_numbers(case, tmp_path):
    mujoco = pytest.importorskip("mujoco")
    from p3d_cli.geometry.rotation import quaternion_matrix

    path, _, robot, result, originals = _fill(case, tmp_path)
    write_fill(robot, result)
    for file, before in originals.items():
        _changed_only_inertials(before, Path(file).read_bytes())
    model = mujoco.MjModel.from_xml_path(str(path))
    filled = [f for f in result.links if f.status == "filled"]
    assert filled
    for f in filled:
        # An unnamed body is named by its MuJoCo body id.
        b = int(f.link[5:]) if f.link.startswith("body#") else model.body(f.link).id
        r = quaternion_matrix(model.body_iquat[b])
        assert model.body_mass[b] == pytest.approx(f.mass, rel=1e-12)
        np.testing.assert_allclose(model.body_ipos[b], f.center, rtol=0, atol=1e-9)
        np.testing.assert_allclose(r @ np.diag(model.body_inertia[b]) @ r.T, f.inertia, rtol=0,
                                   atol=1e-9 * np.abs(f.inertia).max())
    # Run again on the filled files: nothing changes.
    again = fill_robot(load_robot(path), mass_from="declared", density=1000.0, force=True)
    assert {p: Path(p).read_bytes() for p in again.files} == dict(again.files)


@pytest.mark.parametrize("case", ["omniquad", "rover"])
def test_filled_real_sdf_parses_with_p3ds_numbers(case, tmp_path):
    lxml = pytest.importorskip("lxml.etree")
    path, packages, robot, result, originals = _fill(case, tmp_path)
    write_fill(robot, result)
    for file, before in originals.items():
        _changed_only_inertials(before, Path(file).read_bytes())
        lxml.parse(file)  # well-formed
    links = {link.name: link for link in load_robot(path, packages).links}
    for f in result.links:
        if f.status == "filled":
            i = links[f.link].inertial
            assert i.mass == f.mass
            np.testing.assert_allclose(i.center, f.center, rtol=0, atol=1e-15)
            np.testing.assert_allclose(i.inertia, f.inertia, rtol=0, atol=1e-15 * np.abs(f.inertia).max())


def test_collada_visuals_are_read_in_their_unit():
    """kuka's visual meshes are COLLADA (<unit meter="1">, several meshes a file): each link's
    visual geometry is its DAE's, as trimesh reads it, in metres. trimesh's COLLADA reader
    (pycollada) rounds the file's decimal positions to float32 where p3d keeps float64, so the
    two agree to float32's precision (1.5e-6 on link_6's 12 mm thin flange), not to the last
    digit; a unit slip would be a factor of 1e3 or more."""
    pytest.importorskip("collada")
    trimesh = pytest.importorskip("trimesh")
    root = folder("kuka_kr16_2")
    robot = load_robot(root / "kuka_kr16_support/urdf/kr16_2.urdf", {"kuka_kr16_support": str(root / "kuka_kr16_support")})
    from p3d_cli.robots.geometry import measure_link

    for link in robot.links:
        if not link.visual:
            continue
        (geom,) = link.visual
        visual = measure_link(link, "visual", robot.path).result.properties
        peer = trimesh.load(geom.thing, force="mesh")
        assert visual.volume == pytest.approx(peer.volume, rel=1e-5), link.name
