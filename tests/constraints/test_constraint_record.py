"""A constraint type's module is the one record of its keys, its own values, its equations and
their array and scalar forms: a throwaway type registered in ``CONSTRAINT_TYPES`` with nothing
else edited is read from a scene, its keys checked and listed, its rows counted, and a scene
with it solved and stepped on both the array path and the small-scene path; and no module but
a type's own and the registry names a type."""

from __future__ import annotations

import ast
import types

import numpy as np
import pytest
from test_small_step import assert_same, both_paths

from helpers.real_meshes import REPO
from p3d_cli.constraints import ball, bar, hinge, scalar, solve_scene
from p3d_cli.constraints.joint import joint_geometry
from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.constraints.rotation import quat_to_matrix
from p3d_cli.constraints.rows import RowSet
from p3d_cli.constraints.scene import parse_scene
from p3d_cli.errors import SceneError

BODY = {"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}


def read_tether(spec, place, body_a, body_b, attach_a, attach_b):
    if spec.get("slack") is not None and spec["slack"] < 0:
        raise SceneError(f"{place}.slack", "is negative", "give a slack >= 0")
    return {"reach": 1.0 + float(spec.get("slack") or 0.0), "pull": np.array([0.0, 0.0, 1.0])}


class _NoRows:
    """An array form that writes nothing (the row layout and the turned vectors are what is tested)."""

    def __init__(self, specs, ks, offsets):
        pass

    def template(self, ja, jb):
        pass


#: A throwaway type: a ball's keys plus ``slack``, two rows, values of its own (``reach``, and
#: ``pull``: a body-frame vector of side b that its world geometry turns).
TETHER = types.SimpleNamespace(KEYS=("attach_a", "attach_b", "slack"), EQUATIONS=2, read=read_tether, Rows=_NoRows,
                               TURNED=(("pull", "b"),))


@pytest.fixture
def tether(monkeypatch):
    monkeypatch.setitem(CONSTRAINT_TYPES, "tether", TETHER)
    return TETHER


def scene(**entry):
    return parse_scene({"bodies": {"a": dict(BODY), "b": {**BODY, "position": [0, 0, 2]}},
                        "constraints": [{"a": "a", "b": "b", "attach_a": [0, 0, 1], **entry}]}, "scene.yaml", ".")


def test_a_registered_type_is_read_from_a_scene(tether):
    spec = scene(type="tether", slack=0.5).constraints[0]
    assert (spec.type, spec.values["reach"], spec.where) == ("tether", 1.5, "scene.yaml: constraints[0]")
    assert spec.attach_b.tolist() == [0.0, 0.0, -1.0]     # the attachments are read as for every type
    with pytest.raises(SceneError, match=r"constraints\[0\]\.slack: is negative"):
        scene(type="tether", slack=-1)


def test_its_keys_are_the_modules(tether):
    with pytest.raises(SceneError, match=r"unknown key 'axis_a'; known keys here: type, a, b, attach_a, attach_b, slack"):
        scene(type="tether", axis_a=[0, 0, 1])
    with pytest.raises(SceneError, match=r"use one of: ball, hinge, bar, tether"):
        scene(type="rope")


def test_its_rows_are_counted_from_the_module(tether):
    parsed = parse_scene({"bodies": {"a": dict(BODY), "b": {**BODY, "position": [0, 0, 2]}},
                          "constraints": [{"type": "ball", "a": "a", "b": "b", "attach_a": [0, 0, 1]},
                                          {"type": "tether", "a": "a", "b": "b", "attach_a": [0, 0, 1]}]},
                         "scene.yaml", ".")
    rows = RowSet(parsed, {"a": 0, "b": 1}, np.zeros((2, 3)))
    assert rows.offsets.tolist() == [0, 3, 5] and rows.m == 5
    # Its declared vector is turned with side b's rotation (a quarter turn about x: z -> -y).
    quarter = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    geo = rows.geometry(np.zeros((2, 3)), np.stack([np.eye(3), quarter]))
    assert [v.tolist() for v in geo.turned[1]] == [[[0.0, -1.0, 0.0]]]
    single = joint_geometry(parsed.constraints[1], np.zeros(3), np.eye(3), np.zeros(3),
                            np.zeros(3), quarter, np.zeros(3))
    assert [v.tolist() for v in single.turned] == [[0.0, -1.0, 0.0]]


def test_an_unregistered_type_is_refused():
    with pytest.raises(SceneError, match=r"unknown constraint type 'tether'; use one of: ball, hinge, bar$"):
        scene(type="tether")


@pytest.mark.parametrize("module", [ball, hinge, bar])
def test_each_type_declares_its_record(module):
    assert module.KEYS[:2] == ("attach_a", "attach_b") and module.EQUATIONS in (1, 3, 5)
    assert callable(module.read) and callable(module.jacobian) and callable(module.position_error)
    assert issubclass(module.SmallJoint, scalar.Joint) and module.SmallJoint.rows == module.EQUATIONS
    assert callable(module.Rows) and all(side in ("a", "b") for _, side in module.TURNED)
    turned = tuple(np.array([0.0, 0, 1]) for _ in module.TURNED)
    ja, jb = module.jacobian(types.SimpleNamespace(r_a=np.array([0.0, 0, 1]), r_b=np.array([0.0, 0, -1]),
                                                   p_a=np.zeros(3), p_b=np.array([0.0, 0, 1]),
                                                   turned=turned, where="x"))
    assert ja.shape == jb.shape == (module.EQUATIONS, 6)


# -- a whole type, from this one place -----------------------------------------------------------
# "pin": the two attachment points keep the same height (z), one row. Velocity equation:
# (v_b + ω_b × r_b - v_a - ω_a × r_a)_z = 0, and (ω × r)_z = ω_x r_y - ω_y r_x.


def _pin_jacobian(geo):
    ja, jb = np.zeros((1, 6)), np.zeros((1, 6))
    ja[0, 2], ja[0, 3], ja[0, 4] = -1.0, -geo.r_a[1], geo.r_a[0]
    jb[0, 2], jb[0, 3], jb[0, 4] = 1.0, geo.r_b[1], -geo.r_b[0]
    return ja, jb


class _PinRows:
    def __init__(self, specs, ks, offsets):
        self.ks, self.rows = ks, offsets[ks]

    def template(self, ja, jb):
        ja[self.rows, 2], jb[self.rows, 2] = -1.0, 1.0

    def errors(self, geo, g, out):
        out[self.rows] = geo.gap[self.ks, 2]

    def jacobian(self, geo, g, ja, jb):
        r_a, r_b = geo.r_a[self.ks], geo.r_b[self.ks]
        ja[self.rows, 3], ja[self.rows, 4] = -r_a[:, 1], r_a[:, 0]
        jb[self.rows, 3], jb[self.rows, 4] = r_b[:, 1], -r_b[:, 0]


class _PinJoint(scalar.Joint):
    __slots__ = ()
    rows = 1
    constants = ((0, 2),)

    def evaluate(self, com, rot):
        return [self.points(com, rot)[2]]

    def columns(self):
        return [(0, 3), (0, 4)]

    def entries(self):
        ra, rb = self._state
        out = [-ra[1], ra[0]] if self.free_a else []
        return out + ([rb[1], -rb[0]] if self.free_b else [])


PIN = types.SimpleNamespace(
    KEYS=("attach_a", "attach_b"), EQUATIONS=1, TURNED=(), read=lambda spec, place, body_a, body_b, attach_a, attach_b: {},
    jacobian=_pin_jacobian, position_error=lambda spec, geo: np.array([geo.p_b[2] - geo.p_a[2]]),
    impulse=lambda geo, lam: {"impulse": float(lam[0])}, Rows=_PinRows, SmallJoint=_PinJoint)

PINNED = {
    "gravity": [0, 0, -9.81],
    "bodies": {
        "ground": {"fixed": True},
        "arm": {"mass": 2.0, "inertia": [[0.3, 0.05, 0], [0.05, 0.2, 0], [0, 0, 0.4]], "position": [0.5, 0, 0],
                "velocity": [0, 0.3, 0.1], "angular_velocity": [0.2, -0.1, 1.0]},
        "bob": {"mass": 1.0, "inertia": [0.1, 0.2, 0.25], "position": [1.2, 0.1, 0.05],
                "rotation": {"axis": [1, 2, 3], "degrees": 30}, "velocity": [0.5, -1, 2], "angular_velocity": [1, 0, 0]},
    },
    "constraints": [
        {"type": "ball", "a": "ground", "b": "arm", "attach_a": [0, 0, 0]},
        {"type": "pin", "a": "arm", "b": "bob", "attach_a": [0.5, 0, 0], "attach_b": [-0.2, 0.1, 0]},
    ],
}


def _point_velocity(state, attach):
    """A body point's world velocity from a reported state: v + ω × (R attach + origin - centre)."""
    r = state.position + quat_to_matrix(state.rotation) @ np.asarray(attach, dtype=np.float64) - state.center_of_mass
    return state.velocity + np.cross(state.angular_velocity, r)


def test_a_registered_type_is_solved_and_stepped_on_both_paths(monkeypatch):
    monkeypatch.setitem(CONSTRAINT_TYPES, "pin", PIN)
    scene = parse_scene(PINNED, "scene.yaml", ".")
    solved = solve_scene(scene, on_step=lambda t, bodies: None)
    states = {b.name: b for b in solved.bodies}
    pin = PINNED["constraints"][1]
    # The velocity solve leaves the points no relative vertical velocity (an independent oracle).
    relative = _point_velocity(states["bob"], pin["attach_b"]) - _point_velocity(states["arm"], pin["attach_a"])
    assert abs(relative[2]) < 1e-12 and (solved.equations, solved.rank) == (4, 4)
    fast, slow, taken = both_paths(scene, steps=20, dt=1e-3, on_step=lambda t, bodies: None)
    assert taken, "the scene of two free bodies takes the small step"
    assert_same(fast, slow, 1e-12, 1e-9)
    for result in (fast, slow):
        states = {b.name: b for b in result.bodies}
        world = [states[n].position + quat_to_matrix(states[n].rotation) @ np.asarray(pin[k], dtype=np.float64)
                 for n, k in (("arm", "attach_a"), ("bob", "attach_b"))]
        assert abs(world[1][2] - world[0][2]) < 1e-12 and result.max_position_error < 1e-12
        assert result.constraints[1].type == "pin" and np.isfinite(result.constraints[1].impulse)


def test_no_module_but_the_types_and_the_registry_names_a_type():
    """The solver, the rows, the small step, the scene reader, the commands and the pictures loop
    over ``CONSTRAINT_TYPES``: none imports a type's module or names a type."""
    own = {"ball", "hinge", "bar", "registry"}
    found = []
    for folder in ("constraints", "cli", "render"):
        for path in sorted((REPO / "p3d_cli" / folder).glob("*.py")):
            if folder == "constraints" and path.stem in own:
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                named = (isinstance(node, ast.Constant) and node.value in CONSTRAINT_TYPES
                         or isinstance(node, ast.ImportFrom) and node.module == "p3d_cli.constraints"
                         and any(a.name in CONSTRAINT_TYPES for a in node.names)
                         or isinstance(node, ast.ImportFrom) and node.module is not None
                         and node.module.rsplit(".", 1)[-1] in CONSTRAINT_TYPES
                         and node.module.startswith("p3d_cli.constraints."))
                if named:
                    found.append(f"{path.relative_to(REPO)}:{node.lineno}")
    assert found == []
