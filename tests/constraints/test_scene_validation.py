"""Every bad scene is refused before any work, with one error naming its place."""

from __future__ import annotations

import textwrap

import pytest

from p3d_cli.constraints import load_scene
from p3d_cli.errors import SceneError

GOOD = """\
bodies:
  base: {fixed: true}
  arm: {mass: 2.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]], position: [0, 0, -0.5]}
constraints:
  - {type: ball, a: base, b: arm, attach_a: [0, 0, 0], attach_b: [0, 0, 0.5]}
"""


def load(tmp_path, text: str, name: str = "scene.yaml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return load_scene(str(path), name)


def refused(tmp_path, text: str) -> SceneError:
    with pytest.raises(SceneError) as info:
        load(tmp_path, text)
    assert "\n" not in info.value.message
    return info.value


def test_good_scene_loads(tmp_path):
    scene = load(tmp_path, GOOD)
    assert [b.name for b in scene.bodies] == ["base", "arm"]
    assert scene.constraints[0].type == "ball"


@pytest.mark.parametrize("text, where, what", [
    (GOOD.replace("arm: {mass", "arm: {colour: red, mass"), "scene.yaml: bodies.arm.colour", "unknown key"),
    (GOOD + "extra: 1\n", "scene.yaml: extra", "unknown key 'extra'"),
    (GOOD.replace("b: arm,", "b: arm2,"), "scene.yaml: constraints[0].b", "no body named 'arm2'"),
    (GOOD.replace("b: arm,", "b: base,"), "scene.yaml: constraints[0].b", "to itself"),
    (GOOD.replace("mass: 2.0", "mass: 0"), "scene.yaml: bodies.arm.mass", "must be positive"),
    (GOOD.replace("mass: 2.0", "mass: -1"), "scene.yaml: bodies.arm.mass", "must be positive"),
    (GOOD.replace("mass: 2.0", "mass: heavy"), "scene.yaml: bodies.arm.mass", "expected a number"),
    (GOOD.replace("[0, 0.1, 0]", "[0.05, 0.1, 0]"), "scene.yaml: bodies.arm.inertia", "not symmetric"),
    (GOOD.replace("[0, 0, 0.02]", "[0, 0, -0.02]"), "scene.yaml: bodies.arm.inertia", "not positive definite"),
    (GOOD.replace("[0, 0, 0.02]", "[0, 0, 0.5]"), "scene.yaml: bodies.arm.inertia", "triangle inequality"),
    (GOOD.replace("[0, 0, 0.02]]", "[0, 0]]"), "scene.yaml: bodies.arm.inertia", "3×3"),
    (GOOD.replace("position: [0, 0, -0.5]", "position: [0, 0]"), "scene.yaml: bodies.arm.position", "three numbers"),
    (GOOD.replace("type: ball", "type: slider"), "scene.yaml: constraints[0].type", "unknown constraint type"),
    (GOOD.replace("type: ball, ", ""), "scene.yaml: constraints[0].type", "has no type"),
    (GOOD.replace("a: base, ", ""), "scene.yaml: constraints[0].a", "missing"),
    (GOOD.replace("attach_a: [0, 0, 0], attach_b: [0, 0, 0.5]", "axis_a: [0, 0, 1]"),
     "scene.yaml: constraints[0].axis_a", "unknown key"),
    (GOOD.replace("base: {fixed: true}", "base: {fixed: yes please}"), "scene.yaml: bodies.base.fixed", "true or false"),
    (GOOD.replace("arm: {mass: 2.0, ", "arm: {"), "scene.yaml: bodies.arm", "has no mass"),
    (GOOD.replace("inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]], ", ""), "scene.yaml: bodies.arm", "has no inertia"),
    (GOOD.replace("base: {fixed: true}", "base: {fixed: true, velocity: [1, 0, 0]}"),
     "scene.yaml: bodies.base.velocity", "never moves"),
    (GOOD.replace("position: [0, 0, -0.5]}", "position: [0, 0, -0.5], rotation: {quat: [0, 0, 0, 0]}}"),
     "scene.yaml: bodies.arm.rotation.quat", "zero"),
    (GOOD.replace("position: [0, 0, -0.5]}", "position: [0, 0, -0.5], rotation: {axis: [0, 0, 0], degrees: 3}}"),
     "scene.yaml: bodies.arm.rotation.axis", "zero vector"),
    (GOOD.replace("position: [0, 0, -0.5]}", "position: [0, 0, -0.5], density: 3}"),
     "scene.yaml: bodies.arm.density", "both density and mass"),
    (GOOD.replace("base: {fixed: true}", "base: {fixed: true, density: 3}"),
     "scene.yaml: bodies.base.density", "needs a shape"),
    (GOOD.split("constraints:")[0] + "constraints: 3\n", "scene.yaml: constraints", "expected a list"),
    (GOOD.replace("arm: {mass: 2.0,", "arm: {shape: parts/missing.stl, mass: 2.0,"),
     "scene.yaml: bodies.arm.shape", "no such mesh file"),
    ("- just\n- a list\n", "scene.yaml", "expected a mapping"),
    ("bodies: {}\n", "scene.yaml: bodies", "expected a mapping of name"),
    (GOOD.replace("constraints:\n", "x: 1\nconstraints:\n"), "scene.yaml: x", "unknown key 'x'"),
])
def test_bad_scene_gets_one_line_naming_the_place(tmp_path, text, where, what):
    error = refused(tmp_path, text)
    assert error.where.startswith(where)
    assert what in error.what
    assert error.hint


def test_body_named_twice_is_caught_not_silently_merged(tmp_path):
    text = GOOD.replace("  arm: {", "  arm: {mass: 1, inertia: [1, 1, 1]}\n  arm: {")
    error = refused(tmp_path, text)
    assert error.where == "scene.yaml:4"
    assert "'arm' appears twice" in error.what


def test_error_lists_known_bodies(tmp_path):
    error = refused(tmp_path, GOOD.replace("b: arm,", "b: arm2,"))
    assert error.message == ("scene.yaml: constraints[0].b: no body named 'arm2'; bodies are: base, arm")


def test_yaml_is_read_safely(tmp_path):
    # A python object tag must never be constructed.
    error = refused(tmp_path, "bodies: !!python/object/apply:os.system ['echo hacked']\n")
    assert "not valid YAML" in error.what


def test_bad_yaml_syntax_names_the_line(tmp_path):
    error = refused(tmp_path, "bodies:\n  arm: {mass: 1\n")
    assert error.where.startswith("scene.yaml:")
    assert "not valid YAML" in error.what


def test_zero_length_bar_and_coincident_points_are_refused(tmp_path):
    bar = GOOD.replace("type: ball", "type: bar").replace("attach_b: [0, 0, 0.5]}", "attach_b: [0, 0, 0.5], length: 0}")
    error = refused(tmp_path, bar)
    assert error.where == "scene.yaml: constraints[0].length" and "no direction" in error.what
    coincide = GOOD.replace("type: ball", "type: bar").replace("attach_b: [0, 0, 0.5]}", "attach_b: [0, 0, 0.5], length: 1}")
    coincide = coincide.replace("position: [0, 0, -0.5]", "position: [0, 0, -0.5]")
    # attachments at (0,0,0) and (0,0,-0.5+0.5): the same point
    error = refused(tmp_path, coincide)
    assert "coincide" in error.what


def test_zero_hinge_axis_is_refused(tmp_path):
    hinge = GOOD.replace("type: ball", "type: hinge").replace("attach_b: [0, 0, 0.5]}",
                                                              "attach_b: [0, 0, 0.5], axis_a: [0, 0, 0]}")
    error = refused(tmp_path, hinge)
    assert error.where == "scene.yaml: constraints[0].axis_a" and "zero vector" in error.what


def test_two_fixed_bodies_cannot_be_linked(tmp_path):
    error = refused(tmp_path, GOOD.replace("arm: {mass", "arm: {fixed: true, mass"))
    assert "two fixed bodies" in error.what


def test_missing_attachment_defaults_to_the_same_world_point(tmp_path):
    scene = load(tmp_path, GOOD.replace(", attach_b: [0, 0, 0.5]", "").replace(
        "position: [0, 0, -0.5]}", "position: [0, 0, -0.5], rotation: {axis: [1, 0, 0], degrees: 90}}"))
    # World point (0, 0, 0) seen from arm (origin (0, 0, -0.5), turned 90° about x): (0, 0.5, 0).
    assert scene.constraints[0].attach_b == pytest.approx([0, 0.5, 0], abs=1e-15)


def test_bad_mesh_file_is_refused_when_read(tmp_path):
    from p3d_cli.constraints import solve_scene

    (tmp_path / "broken.stl").write_bytes(b"solid x\nfacet normal 0 0 0\n outer loop\n vertex 1 2\n")
    scene = load(tmp_path, GOOD.replace("arm: {mass: 2.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]],",
                                        "arm: {shape: broken.stl,"))
    with pytest.raises(SceneError) as info:
        solve_scene(scene)
    assert info.value.where == "scene.yaml: bodies.arm.shape"
    assert "broken.stl" in info.value.what
