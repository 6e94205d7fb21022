"""A scene body made of parts (the assembly-file part syntax) and the placement vocabulary of
parts and the command line (``translate``, ``rotate``, ``quat``, ``rpy``) for a body's pose."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers.meshes import cube_triangles, write_binary_stl

from p3d_cli.constraints import load_scene, parse_scene, solve_scene
from p3d_cli.constraints.bodies import resolve_inertials
from p3d_cli.errors import SceneError
from p3d_cli.geometry.rotation import rotation_from_rpy


def _box(m: float, half) -> tuple[float, np.ndarray]:
    a, b, c = half
    return m, m / 3 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def _whole(pieces) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre and inertia about the centre of (mass, inertia about own centre (body
    axes), rotation to the body frame, centre in the body frame) pieces: parallel-axis sums."""
    mass = sum(m for m, _, _, _ in pieces)
    com = sum(m * np.asarray(c) for m, _, _, c in pieces) / mass
    inertia = np.zeros((3, 3))
    for m, i, r, c in pieces:
        d = np.asarray(c) - com
        inertia += r @ i @ r.T + m * (d @ d * np.eye(3) - np.outer(d, d))
    return mass, com, inertia


def _inertial(text: str, directory=".", name="arm"):
    scene = parse_scene(__import__("yaml").safe_load(text), "scene.yaml", str(directory))
    return resolve_inertials([scene.body(name)])[name]


def test_parts_body_is_its_parts_summed_with_the_parallel_axis_theorem():
    got = _inertial("""
bodies:
  arm:
    density: 1000              # the default of parts that give none
    parts:
      - {name: rod, shape: 'box:0.05,0.05,0.5', translate: [0, 0, -0.5]}
      - {name: bob, shape: 'sphere:0.1', density: 7850, translate: [0, 0, -1]}
      - {name: fin, shape: 'box:0.2,0.01,0.1', mass: 0.25, rotate: {axis: z, degrees: 30},
         translate: [0.1, 0, -0.9]}
""")
    rod = _box(1000 * 0.1 * 0.1 * 1.0, (0.05, 0.05, 0.5))
    m_bob = 7850 * 4 / 3 * math.pi * 0.1 ** 3
    fin = _box(0.25, (0.2, 0.01, 0.1))
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    mass, com, inertia = _whole([
        (*rod, np.eye(3), (0, 0, -0.5)),
        (m_bob, 0.4 * m_bob * 0.01 * np.eye(3), np.eye(3), (0, 0, -1)),
        (*fin, turn, (0.1, 0, -0.9)),
    ])
    assert got.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(got.center_of_mass, com, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.inertia, inertia, rtol=0, atol=1e-12 * np.abs(inertia).max())


def test_mass_is_the_whole_body_and_given_inertia_and_centre_override_the_parts():
    got = _inertial("""
bodies:
  arm:
    mass: 3
    parts: [{shape: 'box:1,1,1'}, {shape: 'box:1,1,1', translate: [2, 0, 0]}]
""")
    assert got.mass == pytest.approx(3.0, rel=1e-15)
    np.testing.assert_allclose(got.center_of_mass, [1, 0, 0], atol=1e-15)
    # Two cubes of 1.5 each, their centres 1 from the whole's: 2·(1.5·(2/3)) + 2·1.5·1² about y.
    np.testing.assert_allclose(np.diag(got.inertia), [2.0, 5.0, 5.0], rtol=1e-14)
    given = _inertial("""
bodies:
  arm: {parts: [{shape: box}], inertia: [1, 2, 3], center_of_mass: [0, 0, 0.5]}
""")
    np.testing.assert_array_equal(np.diag(given.inertia), [1, 2, 3])
    np.testing.assert_array_equal(given.center_of_mass, [0, 0, 0.5])
    assert given.mass == pytest.approx(8.0)


def test_parts_take_meshes_relative_to_the_scene_nested_assemblies_and_mirrors(tmp_path):
    write_binary_stl(tmp_path / "cube.stl", cube_triangles())        # [0, 1]³
    (tmp_path / "pair.yaml").write_text("parts:\n  - {mesh: cube.stl}\n  - {mesh: cube.stl, translate: [1, 0, 0]}\n")
    got = _inertial("""
bodies:
  arm:
    parts:
      - {assembly: pair.yaml, density: 2}
      - {mesh: cube.stl, scale: [-1, 1, 1], density: 2}     # mirrored to [-1, 0] x [0, 1]²
""", tmp_path)
    # Three unit cubes side by side, [-1, 2] x [0, 1]²: a 3 x 1 x 1 block of density 2.
    mass, inertia = _box(6.0, (1.5, 0.5, 0.5))
    assert got.mass == pytest.approx(mass, rel=1e-15)
    np.testing.assert_allclose(got.center_of_mass, [0.5, 0.5, 0.5], atol=1e-15)
    np.testing.assert_allclose(got.inertia, inertia, atol=1e-14)


def test_a_parts_body_moves_as_the_same_body_given_by_numbers():
    parts = """
gravity: [0, 0, -9.81]
bodies:
  base: {fixed: true}
  arm:
    parts:
      - {shape: 'box:0.05,0.05,0.5', density: 1000, translate: [0, 0, -0.5]}
      - {shape: 'sphere:0.1', density: 7850, translate: [0, 0, -1], rotate: z:10}
    rotation: {axis: [1, 0, 0], degrees: 30}
    velocity: [1, 0, 0]
constraints:
  - {type: ball, a: base, b: arm, attach_a: [0, 0, 0], attach_b: [0, 0, 0]}
"""
    data = __import__("yaml").safe_load(parts)
    whole = resolve_inertials([parse_scene(data, "s", ".").body("arm")])["arm"]
    arm = data["bodies"]["arm"]
    del arm["parts"]
    arm.update(mass=whole.mass, inertia=whole.inertia.tolist(), center_of_mass=whole.center_of_mass.tolist())
    a = solve_scene(parse_scene(__import__("yaml").safe_load(parts), "s", "."), steps=200, dt=0.001)
    b = solve_scene(parse_scene(data, "s", "."), steps=200, dt=0.001)
    # The same numbers up to the rounding of reading the inertia back from text.
    for x, y in zip(a.bodies, b.bodies):
        np.testing.assert_allclose(x.position, y.position, rtol=0, atol=1e-13)
        np.testing.assert_allclose(x.velocity, y.velocity, rtol=0, atol=1e-13)
    assert a.kinetic_energy == pytest.approx(b.kinetic_energy, rel=1e-13)


@pytest.mark.parametrize("pose, same", [
    ("translate: [1, 2, 3]", "position: [1, 2, 3]"),
    ("rotate: {axis: z, degrees: 90}", "rotation: {axis: [0, 0, 1], degrees: 90}"),
    ("rotate: x:30", "rotation: {axis: [1, 0, 0], degrees: 30}"),
    ("quat: [0.5, 0.5, 0.5, 0.5]", "rotation: {quat: [0.5, 0.5, 0.5, 0.5]}"),
])
def test_the_placement_vocabulary_is_a_body_pose(pose, same):
    def body(text):
        return parse_scene(__import__("yaml").safe_load(f"bodies:\n  b: {{fixed: true, {text}}}\n"), "s", ".").body("b")

    a, b = body(pose), body(same)
    np.testing.assert_allclose(a.position, b.position, rtol=0, atol=0)
    np.testing.assert_allclose(a.rotation, b.rotation, rtol=0, atol=2e-16)


def test_rpy_pose_is_the_urdf_rotation():
    from p3d_cli.geometry.rotation import quaternion_matrix

    body = parse_scene(__import__("yaml").safe_load("bodies:\n  b: {fixed: true, rpy: [0.1, -0.7, 2.0]}\n"),
                       "s", ".").body("b")
    np.testing.assert_allclose(quaternion_matrix(body.rotation), rotation_from_rpy(0.1, -0.7, 2.0), atol=1e-15)


@pytest.mark.parametrize("body, where, what", [
    ("{shape: box, parts: [{shape: box}]}", "bodies.arm.parts", "given with shape"),
    ("{parts: []}", "bodies.arm.parts", "not a list of parts"),
    ("{parts: box}", "bodies.arm.parts", "not a list of parts"),
    ("{parts: [{shape: box}, {shape: box, mass: -1}]}", "bodies.arm.parts[1].mass", ""),
    ("{parts: [{shape: box}, {shape: box, color: red}]}", "bodies.arm.parts[1].color", "unknown key"),
    ("{parts: [{shape: 'box:1,x,1'}]}", "bodies.arm.parts[0].shape", ""),
    ("{parts: [{mesh: missing.stl}]}", "bodies.arm.parts[0].mesh", "no such file"),
    ("{parts: [{shape: box, translate: [1, 2]}]}", "bodies.arm.parts[0].translate", "3"),
    ("{parts: [{shape: box}], position: [0, 0, 0], translate: [1, 0, 0]}", "bodies.arm.translate", "position"),
    ("{parts: [{shape: box}], rotation: {quat: [1, 0, 0, 0]}, rpy: [0, 0, 1]}", "bodies.arm.rpy", "rotation"),
    ("{mass: 1, inertia: [1, 1, 1], rotate: {axis: q, degrees: 3}}", "bodies.arm.rotate", ""),
    ("{mass: 1, inertia: [1, 1, 1], quat: [0, 0, 0, 0]}", "bodies.arm.quat", ""),
    ("{parts: [{shape: box, density: 7.85 g/cm^3}]}", "bodies.arm.parts[0].density", "has a unit"),
])
def test_bad_parts_and_poses_are_one_scene_error_naming_the_key(tmp_path, body, where, what):
    path = tmp_path / "scene.yaml"
    path.write_text(f"bodies:\n  arm: {body}\nconstraints: []\n")
    with pytest.raises(SceneError) as info:
        scene = load_scene(str(path), "scene.yaml")
        resolve_inertials([scene.body("arm")])
    assert info.value.where == f"scene.yaml: {where}"
    assert what in info.value.what


@pytest.mark.parametrize("mesh, what", [("open.stl", "not closed"), ("inward.stl", "negative")])
def test_parts_that_are_not_solids_are_refused_as_a_shape_would_be(tmp_path, mesh, what):
    write_binary_stl(tmp_path / "inward.stl", cube_triangles()[:, ::-1])     # wound inward
    write_binary_stl(tmp_path / "open.stl", cube_triangles()[:-1])           # one face missing
    path = tmp_path / "scene.yaml"
    path.write_text(f"bodies:\n  arm: {{parts: [{{shape: box}}, {{mesh: {mesh}}}], velocity: [1, 0, 0]}}\n")
    with pytest.raises(SceneError) as info:
        solve_scene(load_scene(str(path), "scene.yaml"))
    assert info.value.where == "scene.yaml: bodies.arm.parts[1]"
    assert what in info.value.what


def test_solve_command_reads_a_parts_body(tmp_path):
    from click.testing import CliRunner

    from p3d_cli.cli.main import cli

    path = tmp_path / "scene.yaml"
    path.write_text("""
bodies:
  ground: {fixed: true}
  arm:
    parts: [{shape: 'box:0.5,0.05,0.05', mass: 2, translate: [0.5, 0, 0]}]
    angular_velocity: [0, 0, 1]
constraints:
  - {type: hinge, a: ground, b: arm, attach_a: [0, 0, 0], attach_b: [0, 0, 0], axis_a: [0, 0, 1], axis_b: [0, 0, 1]}
""")
    out = CliRunner().invoke(cli, ["solve", str(path), "--json"])
    assert out.exit_code == 0, out.output
    record = __import__("json").loads(out.output)
    assert record["rank"] == 5


def test_the_documented_scene_format_loads_and_solves(tmp_path):
    import re
    from pathlib import Path

    docs = (Path(__file__).resolve().parents[2] / "docs" / "solve.md").read_text()
    block = re.search(r"## The scene file\n\n```yaml\n(.*?)```", docs, re.S).group(1)
    (tmp_path / "scene.yaml").write_text(block)
    write_binary_stl(tmp_path / "weight.stl", cube_triangles() * 0.01)
    scene = load_scene(str(tmp_path / "scene.yaml"), "scene.yaml")
    hand = scene.body("hand")
    np.testing.assert_array_equal(hand.position, [0, 0, -1.0])
    inertial = resolve_inertials([hand])["hand"]
    assert inertial.mass == pytest.approx(2700 * 0.08 * 0.1 * 0.02 + 0.2, rel=1e-12)
    assert solve_scene(scene).rank > 0


def test_numbers_without_a_dot_in_the_exponent_are_numbers(tmp_path):
    """YAML 1.1 (PyYAML) reads ``1e8`` as text; scenes and assemblies read it as every language
    (and YAML 1.2) does, and keep quoted text as text."""
    from p3d_cli.io.yaml_loader import read_yaml

    path = tmp_path / "n.yaml"
    path.write_text("a: [1e8, -2.5e-3, +3E2, 1.0e+8, 7, 1_0, '1e8', 1e, e5, 0x10]\n")
    assert read_yaml(str(path), "n.yaml")["a"] == [1e8, -2.5e-3, 300.0, 1e8, 7, 10, "1e8", "1e", "e5", 16]
    scene = tmp_path / "scene.yaml"
    scene.write_text("bodies:\n  b: {mass: 2e0, inertia: [1e-1, 1e-1, 1e-1], position: [1e3, 0, 0]}\n")
    body = load_scene(str(scene)).body("b")
    assert body.mass == 2.0 and body.position[0] == 1000.0
    scene.write_text("bodies:\n  b: {mass: 1e400, inertia: [1, 1, 1]}\n")
    with pytest.raises(SceneError, match="not finite"):
        load_scene(str(scene))


def test_parts_bodies_are_measured_only_when_the_solve_needs_them(monkeypatch):
    from p3d_cli.measure.assembly import whole

    calls = []
    real = whole.assembly_props
    monkeypatch.setattr(whole, "assembly_props", lambda *a, **k: calls.append(a[0].source) or real(*a, **k))
    scene = parse_scene(__import__("yaml").safe_load("""
bodies:
  ground: {fixed: true, parts: [{shape: box}]}
  resting: {parts: [{shape: box}], position: [9, 9, 9]}
  arm: {parts: [{shape: 'box:1,0.1,0.1', translate: [1, 0, 0]}], angular_velocity: [0, 0, 1]}
constraints:
  - {type: ball, a: ground, b: arm, attach_a: [0, 0, 0], attach_b: [0, 0, 0]}
"""), "s", ".")
    solve_scene(scene)
    assert calls == ["s: bodies.arm"]


@pytest.mark.parametrize("value", ["0b_", "2001-13-45", "0x_"])
def test_plain_scalars_yaml_cannot_build_are_one_scene_error(tmp_path, value):
    """PyYAML takes these for a binary int or a date, then fails to build them with a bare
    ValueError (found by fuzzing the scene loader)."""
    from p3d_cli.io.yaml_loader import read_yaml

    path = tmp_path / "s.yaml"
    path.write_text(f"bodies:\n  a: {{fixed: true, position: [{value}, 0, 0]}}\n")
    try:
        read_yaml(str(path), "s.yaml")
    except SceneError as exc:
        assert exc.where == "s.yaml" and "quote it" in exc.hint
    else:   # a PyYAML that reads it as text: the scene then refuses it as no number
        with pytest.raises(SceneError):
            load_scene(str(path))
