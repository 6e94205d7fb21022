"""A constraint type's module is the one record of its keys, its own values and its row count: a
throwaway type registered in ``CONSTRAINT_TYPES`` with nothing else edited is read from a scene,
its keys checked and listed, and its rows counted."""

from __future__ import annotations

import types

import numpy as np
import pytest

from p3d_cli.constraints import ball, bar, hinge
from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.constraints.rows import RowSet
from p3d_cli.constraints.scene import parse_scene
from p3d_cli.errors import SceneError

BODY = {"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}


def read_tether(spec, place, body_a, body_b, attach_a, attach_b):
    if spec.get("slack") is not None and spec["slack"] < 0:
        raise SceneError(f"{place}.slack", "is negative", "give a slack >= 0")
    return {"length": 1.0 + float(spec.get("slack") or 0.0)}


#: A throwaway type: a ball's keys plus ``slack``, two rows.
TETHER = types.SimpleNamespace(KEYS=("attach_a", "attach_b", "slack"), EQUATIONS=2, read=read_tether)


@pytest.fixture
def tether(monkeypatch):
    monkeypatch.setitem(CONSTRAINT_TYPES, "tether", TETHER)
    return TETHER


def scene(**entry):
    return parse_scene({"bodies": {"a": dict(BODY), "b": {**BODY, "position": [0, 0, 2]}},
                        "constraints": [{"a": "a", "b": "b", "attach_a": [0, 0, 1], **entry}]}, "scene.yaml", ".")


def test_a_registered_type_is_read_from_a_scene(tether):
    spec = scene(type="tether", slack=0.5).constraints[0]
    assert (spec.type, spec.length, spec.where) == ("tether", 1.5, "scene.yaml: constraints[0]")
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


def test_an_unregistered_type_is_refused():
    with pytest.raises(SceneError, match=r"unknown constraint type 'tether'; use one of: ball, hinge, bar$"):
        scene(type="tether")


@pytest.mark.parametrize("module", [ball, hinge, bar])
def test_each_type_declares_its_record(module):
    assert module.KEYS[:2] == ("attach_a", "attach_b") and module.EQUATIONS in (1, 3, 5)
    assert callable(module.read) and callable(module.jacobian) and callable(module.position_error)
    ja, jb = module.jacobian(types.SimpleNamespace(r_a=np.array([0.0, 0, 1]), r_b=np.array([0.0, 0, -1]),
                                                   p_a=np.zeros(3), p_b=np.array([0.0, 0, 1]),
                                                   z_a=np.array([0.0, 0, 1]), z_b=np.array([0.0, 0, 1]), where="x"))
    assert ja.shape == jb.shape == (module.EQUATIONS, 6)
