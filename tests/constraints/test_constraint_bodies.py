"""Mass properties are computed only when a solve needs them, once per distinct mesh."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli.constraints import load_scene, solve_scene
from p3d_cli.constraints import bodies as bodies_module


@pytest.fixture
def cube_scene(tmp_path):
    """Three bodies sharing one mesh (the unit cube [0, 1]³) and one given by plain numbers."""
    write_binary_stl(tmp_path / "cube.stl", cube_triangles())
    (tmp_path / "scene.yaml").write_text("""
bodies:
  ground: {fixed: true, shape: cube.stl}
  one: {shape: cube.stl, density: 2, velocity: [1, 0, 0]}
  two: {shape: ./cube.stl, mass: 3, position: [2, 0, 0]}
  plain: {shape: cube.stl, mass: 1, inertia: [1, 1, 1], center_of_mass: [0, 0, 0], position: [4, 0, 0]}
  resting: {shape: cube.stl, position: [9, 9, 9]}
constraints:
  - {type: ball, a: one, b: two, attach_a: [1, 0.5, 0.5], attach_b: [0, 0.5, 0.5]}
  - {type: ball, a: two, b: plain, attach_a: [1, 0.5, 0.5]}
  - {type: ball, a: ground, b: plain, attach_b: [0.5, 0, 0]}
""")
    return load_scene(str(tmp_path / "scene.yaml"), "scene.yaml")


@pytest.fixture
def integrated(monkeypatch):
    """The ``(spec, where)`` of every shape the scene's bodies integrate, in order."""
    calls = []
    real = bodies_module.shape_moments

    def spy(spec, where):
        calls.append((spec, where))
        return real(spec, where)

    monkeypatch.setattr(bodies_module, "shape_moments", spy)
    return calls


def test_each_distinct_mesh_is_integrated_once(cube_scene, tmp_path, integrated):
    result = solve_scene(cube_scene)
    # cube.stl and ./cube.stl are one file: integrated once, for the first body needing it.
    assert [str(pathlib.Path(p).resolve()) for p, _ in integrated] == [str((tmp_path / "cube.stl").resolve())]
    # 'one' (density 2) and 'two' (mass 3) both took the cube's properties; the cube's centre
    # (0.5, 0.5, 0.5) is each body's centre of mass.
    states = {b.name: b for b in result.bodies}
    np.testing.assert_allclose(states["one"].center_of_mass, [0.5, 0.5, 0.5], atol=1e-12)
    assert result.momentum[0] == pytest.approx([2.0, 0, 0])


def test_bodies_that_give_everything_and_fixed_or_resting_bodies_are_never_integrated(cube_scene, integrated):
    solve_scene(cube_scene)
    # Only the one shared mesh for 'one' (the first body needing it): not 'plain' (gives mass,
    # inertia and centre), not 'ground' (fixed), not 'resting' (nothing links or moves it).
    assert [where for _, where in integrated] == ["scene.yaml: bodies.one.shape"]


def test_scene_of_plain_bodies_needs_no_shape_at_all(monkeypatch):
    from p3d_cli.constraints import parse_scene

    def forbidden(*args):
        raise AssertionError("integrated a shape")

    monkeypatch.setattr(bodies_module, "shape_moments", forbidden)
    scene = parse_scene({"bodies": {"g": {"fixed": True},
                                    "m": {"mass": 1, "inertia": [1, 1, 1], "velocity": [0, 0, 1]}},
                         "constraints": [{"type": "ball", "a": "g", "b": "m", "attach_a": [1, 0, 0]}]}, "s", ".")
    result = solve_scene(scene)
    assert result.rank == 3


def test_inward_wound_mesh_is_refused(tmp_path):
    write_binary_stl(tmp_path / "inside_out.stl", cube_triangles()[:, ::-1])
    (tmp_path / "scene.yaml").write_text("""
bodies:
  g: {fixed: true}
  m: {shape: inside_out.stl}
constraints:
  - {type: ball, a: g, b: m, attach_a: [0, 0, 0]}
""")
    scene = load_scene(str(tmp_path / "scene.yaml"), "scene.yaml")
    with pytest.raises(Exception) as info:
        solve_scene(scene)
    assert "negative signed volume" in str(info.value)


def test_primitive_spec_gives_the_box_inertia():
    pytest.importorskip("p3d_cli.shapes")
    from p3d_cli.constraints import parse_scene

    scene = parse_scene({"bodies": {"g": {"fixed": True},
                                    "slab": {"shape": "box:1,1,0.1", "density": 7800, "velocity": [0, 0, 1]}},
                         "constraints": [{"type": "ball", "a": "g", "b": "slab", "attach_a": [0, 0, 0]}]}, "s", ".")
    inertial = bodies_module.resolve_inertials([scene.bodies[1]])["slab"]
    mass = 7800 * 2 * 2 * 0.2
    assert inertial.mass == pytest.approx(mass)
    np.testing.assert_allclose(np.diag(inertial.inertia),
                               [mass * (4 + 0.04) / 12, mass * (4 + 0.04) / 12, mass * 8 / 12], rtol=1e-12)
    # Attached at its own centre to a fixed point: it simply stops.
    result = solve_scene(scene)
    np.testing.assert_allclose(result.bodies[1].velocity, 0, atol=1e-15)


def test_malformed_primitive_spec_names_the_body():
    pytest.importorskip("p3d_cli.shapes")
    from p3d_cli.constraints import parse_scene
    from p3d_cli.errors import SceneError

    with pytest.raises(SceneError) as info:
        parse_scene({"bodies": {"slab": {"shape": "box:1,x,1"}}}, "s.yaml", ".")
    assert info.value.where == "s.yaml: bodies.slab.shape"
