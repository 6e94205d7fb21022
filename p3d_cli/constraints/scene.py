"""A constraint scene: the YAML format of ``p3d solve``, validated into frozen values.

Everything is checked before any work is done, and every problem is one ``SceneError``
naming its place (``scene.yaml: constraints[2].b``). See ``docs/solve.md`` for the format.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from p3d_cli.constraints import values
from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.errors import InputError, SceneError
from p3d_cli.io.yaml_loader import read_yaml

TOP_KEYS = ("gravity", "bodies", "constraints")
BODY_KEYS = ("shape", "parts", "density", "mass", "inertia", "center_of_mass", "fixed", "position",
             "rotation", *values.POSE_KEYS, "velocity", "angular_velocity")


@dataclass(frozen=True)
class BodySpec:
    """One body as the scene gives it; mass properties not yet resolved.

    Attributes
    ----------
    name : str
    where : str
        ``scene.yaml: bodies.<name>``, for messages.
    shape : str or None
        A primitive spec or a mesh path, as written.
    shape_path : str or None
        The mesh path resolved against the scene's folder (None for a primitive spec).
    parts : Assembly or None
        A body made of parts (``parts:``, the syntax of an assembly file's parts, placed in the
        body's frame); then ``density`` is the default of parts that give none and ``mass``
        the whole body's.
    density, mass : float or None
    inertia : (3, 3) float64 or None
        About the centre of mass, body axes.
    center_of_mass : (3,) float64 or None
        Body frame.
    fixed : bool
    position : (3,) float64
        World position of the body frame's origin.
    rotation : (4,) float64
        Unit quaternion ``[w, x, y, z]``, body to world.
    velocity : (3,) float64
        Of the centre of mass, world frame.
    angular_velocity : (3,) float64
        World frame.
    """

    name: str
    where: str
    shape: str | None
    shape_path: str | None
    density: float | None
    mass: float | None
    inertia: np.ndarray | None
    center_of_mass: np.ndarray | None
    fixed: bool
    position: np.ndarray
    rotation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    parts: Any = None

    @property
    def moving(self) -> bool:
        return bool(np.any(self.velocity) or np.any(self.angular_velocity))


@dataclass(frozen=True)
class ConstraintSpec:
    """One constraint; attachments and axes in each body's own frame.

    Attributes
    ----------
    index : int
        Position in the scene's list.
    where : str
        ``scene.yaml: constraints[<index>]``, for messages.
    type : str
        A name of ``CONSTRAINT_TYPES``: ``ball``, ``hinge`` or ``bar``.
    a, b : str
        Body names.
    attach_a, attach_b : (3,) float64
    values : dict
        The type's own values, as its module's ``read`` gives them (a hinge's unit axes
        ``axis_a``, ``axis_b`` in each body's frame; a bar's ``length``). Only the type's module
        reads them, so a new type needs no field here.
    """

    index: int
    type: str
    a: str
    b: str
    attach_a: np.ndarray
    attach_b: np.ndarray
    values: dict = field(default_factory=dict)
    where: str = ""


@dataclass(frozen=True)
class Scene:
    """A validated scene.

    Attributes
    ----------
    where : str
        The scene file's name for messages.
    gravity : (3,) float64
        Zero when the scene gives none.
    bodies : tuple of BodySpec
        In the file's order.
    constraints : tuple of ConstraintSpec
        In the file's order.
    """

    where: str
    gravity: np.ndarray
    bodies: tuple[BodySpec, ...]
    constraints: tuple[ConstraintSpec, ...]

    def body(self, name: str) -> BodySpec:
        for body in self.bodies:
            if body.name == name:
                return body
        raise KeyError(name)


def load_scene(path: str, where: str | None = None) -> Scene:
    """Read and validate a scene file.

    Parameters
    ----------
    path : str
    where : str, optional
        The file's name in messages; default ``path``.

    Raises
    ------
    SceneError
        The first problem found, naming its place.
    """
    where = path if where is None else where
    data = read_yaml(path, where)
    return parse_scene(data, where, os.path.dirname(os.path.abspath(path)))


def parse_scene(data, where: str, directory: str) -> Scene:
    """Validate plain YAML data (dicts, lists, scalars) into a ``Scene``.

    Parameters
    ----------
    data : object
    where : str
        The scene's name in messages.
    directory : str
        Mesh paths are relative to this folder.
    """
    if not isinstance(data, dict):
        raise SceneError(where, f"expected a mapping with 'bodies' and 'constraints', got {values.describe(data)}",
                         "see docs/solve.md for the scene format")
    _known_keys(data, TOP_KEYS, where, "")
    gravity = np.zeros(3)
    if data.get("gravity") is not None:
        gravity = values.vector(data["gravity"], f"{where}: gravity")
    raw_bodies = data.get("bodies")
    if not isinstance(raw_bodies, dict) or not raw_bodies:
        raise SceneError(f"{where}: bodies", f"expected a mapping of name -> body, got {values.describe(raw_bodies)}",
                         "write bodies: {arm: {mass: 1, inertia: [0.1, 0.1, 0.1]}}")
    bodies = tuple(_body(name, spec, where, directory) for name, spec in raw_bodies.items())
    by_name = {b.name: b for b in bodies}
    raw_constraints = data.get("constraints")
    if raw_constraints is None:
        raw_constraints = []
    if not isinstance(raw_constraints, list):
        raise SceneError(f"{where}: constraints", f"expected a list, got {values.describe(raw_constraints)}",
                         "write constraints: [{type: ball, a: base, b: arm, attach_a: [..], attach_b: [..]}]")
    constraints = tuple(_constraint(i, c, where, by_name) for i, c in enumerate(raw_constraints))
    return Scene(where, gravity, bodies, constraints)


def _known_keys(mapping: dict, allowed, where: str, prefix: str) -> None:
    for key in mapping:
        if key not in allowed:
            place = f"{where}: {prefix}{key}" if prefix else f"{where}: {key}"
            raise SceneError(place, f"unknown key {key!r}", "known keys here: " + ", ".join(allowed))


def _body(name, spec, where: str, directory: str) -> BodySpec:
    if not isinstance(name, str) or not name:
        raise SceneError(f"{where}: bodies", f"body name {name!r} is not text",
                         "quote names that look like numbers or booleans: '1': {...}")
    place = f"{where}: bodies.{name}"
    if not isinstance(spec, dict):
        raise SceneError(place, f"expected a mapping of body properties, got {values.describe(spec)}",
                         "known keys: " + ", ".join(BODY_KEYS))
    _known_keys(spec, BODY_KEYS, where, f"bodies.{name}.")
    get = {k: v for k, v in spec.items() if v is not None}
    fixed = get.get("fixed", False)
    if not isinstance(fixed, bool):
        raise SceneError(f"{place}.fixed", f"expected true or false, got {values.describe(fixed)}", "write fixed: true")
    shape = shape_path = parts = None
    if "shape" in get and "parts" in get:
        raise SceneError(f"{place}.parts", "given with shape:", "give one: a shape, or a list of parts")
    if "shape" in get:
        shape, shape_path = _shape(get["shape"], f"{place}.shape", directory)
    if "parts" in get:
        parts = _parts(get["parts"], place, directory)
    solid = shape is not None or parts is not None
    density = values.number(get["density"], f"{place}.density", positive=True) if "density" in get else None
    mass = values.number(get["mass"], f"{place}.mass", positive=True) if "mass" in get else None
    if density is not None and mass is not None:
        raise SceneError(f"{place}.density", "both density and mass are given",
                         "give one: the other follows from the shape's volume")
    if density is not None and not solid:
        raise SceneError(f"{place}.density", "a density needs a shape to give a mass",
                         "add shape: or parts:, or give mass: and inertia: directly")
    inertia = values.inertia(get["inertia"], f"{place}.inertia") if "inertia" in get else None
    com = values.vector(get["center_of_mass"], f"{place}.center_of_mass") if "center_of_mass" in get else None
    if not fixed:
        if mass is None and not solid:
            raise SceneError(place, "has no mass", "give mass: and inertia:, or a shape:, or mark it fixed: true")
        if inertia is None and not solid:
            raise SceneError(place, "has no inertia",
                             "give inertia: (about the centre of mass, body axes), or a shape:")
    position, rotation = values.pose(get, place)
    velocity = values.vector(get["velocity"], f"{place}.velocity") if "velocity" in get else np.zeros(3)
    omega = (values.vector(get["angular_velocity"], f"{place}.angular_velocity")
             if "angular_velocity" in get else np.zeros(3))
    if fixed and (np.any(velocity) or np.any(omega)):
        key = "velocity" if np.any(velocity) else "angular_velocity"
        raise SceneError(f"{place}.{key}", "a fixed body never moves, so it cannot have a velocity",
                         f"remove {key}: or fixed: true")
    return BodySpec(name, place, shape, shape_path, density, mass, inertia, com, fixed, position,
                    rotation, velocity, omega, parts)


def _parts(value, place: str, directory: str):
    """A body made of parts: the assembly-file syntax, in the body's frame."""
    from p3d_cli.measure import parts_assembly

    try:
        parts = parts_assembly(value, place, f"{place}.parts", directory)
    except InputError as exc:
        raise SceneError(exc.where, exc.what, exc.hint) from None
    _bare_amounts(parts)
    return parts


def _bare_amounts(assembly) -> None:
    """A scene has no length unit, so a part's density or mass cannot carry one."""
    from p3d_cli.measure import Assembly
    from p3d_cli.units import has_unit

    for part in assembly.parts:
        for key in ("density", "mass"):
            if has_unit(getattr(part, key)):
                raise SceneError(f"{part.where}.{key}", f"{getattr(part, key)} has a unit, and a scene's numbers "
                                 "have none", "write a bare number in the scene's own units (SI in the examples)")
        if isinstance(part.thing, Assembly):
            _bare_amounts(part.thing)


def _shape(value, where: str, directory: str) -> tuple[str, str | None]:
    if not isinstance(value, str) or not value.strip():
        raise SceneError(where, f"expected a primitive spec or a mesh path, got {values.describe(value)}",
                         "write e.g. box:1,1,0.1 or parts/arm.stl")
    from p3d_cli.constraints.bodies import parse_shape_spec

    if parse_shape_spec(value, where) is not None:
        return value, None
    path = value if os.path.isabs(value) else os.path.join(directory, value)
    if not os.path.isfile(path):
        what = "is a folder, not a mesh file" if os.path.isdir(path) else "no such mesh file"
        raise SceneError(where, f"{what}: {value!r} (looked for {path})",
                         "mesh paths are relative to the scene file; or use a spec such as box:1,1,1")
    if not os.access(path, os.R_OK):
        raise SceneError(where, f"cannot read mesh file {value!r}", "check its permissions")
    return value, path


def _constraint(index: int, spec, where: str, bodies: dict) -> ConstraintSpec:
    place = f"{where}: constraints[{index}]"
    if not isinstance(spec, dict):
        raise SceneError(place, f"expected a mapping, got {values.describe(spec)}",
                         "write {type: ball, a: base, b: arm, attach_a: [..], attach_b: [..]}")
    kind = spec.get("type")
    if not isinstance(kind, str) or kind not in CONSTRAINT_TYPES:
        what = ("has no type" if kind is None else f"unknown constraint type {kind!r}" if isinstance(kind, str)
                else f"expected a type name, got {values.describe(kind)}")
        raise SceneError(f"{place}.type", what, "use one of: " + ", ".join(CONSTRAINT_TYPES))
    module = CONSTRAINT_TYPES[kind]          # the type's keys and its own values are its module's
    allowed = ("type", "a", "b") + module.KEYS
    _known_keys(spec, allowed, where, f"constraints[{index}].")
    names = []
    for side in ("a", "b"):
        name = spec.get(side)
        if name is None:
            raise SceneError(f"{place}.{side}", "missing", f"name the body on side {side}")
        if not isinstance(name, str):     # a list or mapping is not even hashable
            raise SceneError(f"{place}.{side}", f"expected a body name, got {values.describe(name)}",
                             "bodies are: " + ", ".join(bodies))
        if name not in bodies:
            raise SceneError(f"{place}.{side}", f"no body named {name!r}", "bodies are: " + ", ".join(bodies))
        names.append(name)
    a, b = names
    if a == b:
        raise SceneError(f"{place}.b", f"links body {a!r} to itself", "a constraint joins two different bodies")
    if bodies[a].fixed and bodies[b].fixed:
        raise SceneError(place, f"links two fixed bodies ({a!r}, {b!r}), so it can never act",
                         "remove it, or make one body free")
    attach_a, attach_b = values.pair(spec, "attach", place, bodies[a], bodies[b], point=True)
    own = module.read(spec, place, bodies[a], bodies[b], attach_a, attach_b)
    return ConstraintSpec(index, kind, a, b, attach_a, attach_b, own, where=place)
