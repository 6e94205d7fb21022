"""A constraint's scalar form (``small_step.make_joint``) from plain values, for the small-step tests."""

from __future__ import annotations

import types

from p3d_cli.constraints import small_step


def make_joint(kind: str, a: int, b: int, off_a, off_b, free_a: bool, free_b: bool, com, rot, where: str,
               axes=None, length: float = 0.0):
    """The ``SmallJoint`` of a ``kind`` constraint; ``axes`` (body-frame unit axes of a hinge) and
    ``length`` (a bar's) stand for those types' ``ConstraintSpec.values``."""
    own = {"hinge": {"axis_a": axes[0], "axis_b": axes[1]} if axes is not None else {}, "bar": {"length": length}}
    spec = types.SimpleNamespace(type=kind, where=where, values=own.get(kind, {}))
    return small_step.make_joint(spec, a, b, off_a, off_b, free_a, free_b, com, rot)
