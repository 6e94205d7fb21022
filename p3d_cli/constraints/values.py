"""Checking the plain values of a scene file: numbers, vectors, matrices, rotations.

Each function takes the YAML value and the place it came from (``scene.yaml: bodies.arm.mass``)
and returns a numpy value or raises ``SceneError`` naming that place.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints.rotation import quat_from_axis_angle, quat_to_matrix
from p3d_cli.geometry.rotation import quaternion_from_axis_degrees
from p3d_cli.errors import InputError, SceneError
from p3d_cli.geometry.inertia import breaks_triangle_inequality


#: float64's smallest normal number.
TINY = float(np.finfo(np.float64).tiny)


def is_number(value) -> bool:
    # YAML's true/false are Python bools, which are ints: never accept them as numbers.
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def describe(value) -> str:
    """A short description of a wrong value, for messages."""
    if value is None:
        return "nothing"
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return f"a list of {len(value)}"
    if isinstance(value, str):
        return f"the text {value!r}"
    return repr(value)


def number(value, where: str, *, positive: bool = False) -> float:
    """A finite float (``positive``: also > 0)."""
    if not is_number(value):
        raise SceneError(where, f"expected a number, got {describe(value)}", _number_hint(value))
    try:
        x = float(value)
    except OverflowError:  # an integer written out with hundreds of digits
        raise SceneError(where, f"{describe(value)[:40]}... is too large for a float64",
                         "write a finite number") from None
    if not math.isfinite(x):
        raise SceneError(where, f"{value!r} is not finite", "write a finite number")
    if positive and x <= 0:
        raise SceneError(where, f"must be positive, got {value!r}", "write a number greater than 0")
    if positive and x < TINY:
        # A subnormal keeps only a few digits, and its inverse (the solver's) overflows.
        raise SceneError(where, f"{value!r} is below float64's normal range (about 2.2e-308)",
                         "give it in a larger unit")
    return x


def _number_hint(value) -> str:
    """A quoted number (``'1e3'``) is text in YAML; say so."""
    if isinstance(value, str):
        try:
            float(value)
        except ValueError:
            pass
        else:
            return f"{value!r} is quoted, so YAML reads it as text; remove the quotes"
    return "write a plain number such as 2.5"


def vector(value, where: str, *, nonzero: bool = False) -> np.ndarray:
    """A (3,) float64 from a list of three finite numbers (``nonzero``: not the zero vector)."""
    if not isinstance(value, list) or len(value) != 3 or not all(is_number(v) for v in value):
        raise SceneError(where, f"expected three numbers [x, y, z], got {describe(value)}",
                         "write a list like [0, 0, 1]")
    try:
        out = np.array([float(v) for v in value], dtype=np.float64)
    except OverflowError:
        raise SceneError(where, "a component is too large for a float64", "write finite numbers") from None
    if not np.isfinite(out).all():
        raise SceneError(where, "a component is not finite", "write finite numbers")
    if nonzero and not np.any(out):
        raise SceneError(where, "is the zero vector, which has no direction", "give a non-zero direction")
    return out


def unit_vector(v: np.ndarray) -> np.ndarray:
    """``v / |v|``, divided first by its largest component so that the norm neither overflows
    (components near 1e200) nor underflows to 0 (near 1e-300).

    Raises
    ------
    ValueError
        ``v`` is zero or not finite.
    """
    scale = float(np.abs(v).max()) if v.size else 0.0
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError("zero or not finite")
    v = v / scale
    return v / np.linalg.norm(v)


def inertia(value, where: str) -> np.ndarray:
    """A (3, 3) inertia tensor about the centre of mass: symmetric positive definite, and its
    principal moments obey the triangle inequality ``I1 + I2 >= I3`` (every real solid's do).

    A list of three numbers is the diagonal ``[Ixx, Iyy, Izz]``.
    """
    hint = "write [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] or the diagonal [Ixx, Iyy, Izz]"
    if isinstance(value, list) and len(value) == 3 and all(is_number(v) for v in value):
        matrix = np.diag(np.array(value, dtype=np.float64))
    elif (isinstance(value, list) and len(value) == 3
          and all(isinstance(row, list) and len(row) == 3 and all(is_number(v) for v in row) for row in value)):
        matrix = np.array(value, dtype=np.float64)
    else:
        raise SceneError(where, f"expected a 3×3 matrix, got {describe(value)}", hint)
    if not np.isfinite(matrix).all():
        raise SceneError(where, "an entry is not finite", hint)
    scale = float(np.abs(matrix).max())
    if scale == 0.0:
        raise SceneError(where, "is zero", "a body with mass has a positive definite inertia")
    # Differences, halves and the eigen-decomposition are taken of the matrix divided by its
    # largest entry, so that entries near float64's largest do not overflow on the way.
    unit = matrix / scale
    if np.abs(unit - unit.T).max() > 1e-9:
        raise SceneError(where, "is not symmetric", "an inertia tensor has Ixy = Iyx, Ixz = Izx, Iyz = Izy")
    unit = 0.5 * (unit + unit.T)
    matrix = unit * scale
    principal = np.linalg.eigvalsh(unit) * scale
    if principal[0] <= 1e-12 * scale:
        raise SceneError(where, f"is not positive definite (principal moments {_join(principal)})",
                         "every principal moment of a solid is > 0 (p3d uses the positive tensor, "
                         "Ixx = ∫(y²+z²) dm, Ixy = -∫xy dm)")
    if principal[0] < TINY:
        raise SceneError(where, f"principal moment {principal[0]:.3g} is below float64's normal range "
                         "(about 2.2e-308), so its inverse overflows", "give the inertia in a larger unit")
    if breaks_triangle_inequality(principal / scale):     # scale-free: I1 + I2 may overflow
        raise SceneError(where, f"breaks the triangle inequality: principal moments {_join(principal)} "
                         f"have {principal[0]:.6g} + {principal[1]:.6g} < {principal[2]:.6g}",
                         "no solid has such an inertia; check the units and the diagonal")
    return matrix


def rotation(value, where: str) -> np.ndarray:
    """A unit quaternion ``[w, x, y, z]`` from ``{quat: [w, x, y, z]}`` (normalised, must be
    non-zero) or ``{axis: [x, y, z], degrees: A}`` / ``{axis: ..., radians: A}``."""
    hint = "write {quat: [w, x, y, z]} or {axis: [x, y, z], degrees: 30} (or radians:)"
    if not isinstance(value, dict):
        raise SceneError(where, f"expected a mapping, got {describe(value)}", hint)
    keys = set(value)
    if keys == {"quat"}:
        q = value["quat"]
        if not isinstance(q, list) or len(q) != 4 or not all(is_number(v) for v in q):
            raise SceneError(f"{where}.quat", f"expected four numbers [w, x, y, z], got {describe(q)}", hint)
        try:
            return unit_vector(np.array(q, dtype=np.float64))
        except ValueError:
            raise SceneError(f"{where}.quat", "is zero or not finite, so it is no rotation",
                             "the identity is [1, 0, 0, 0]") from None
    angle_keys = keys & {"degrees", "radians"}
    if "axis" in keys and len(angle_keys) == 1 and keys == {"axis"} | angle_keys:
        axis = vector(value["axis"], f"{where}.axis", nonzero=True)
        key = angle_keys.pop()
        angle = number(value[key], f"{where}.{key}")
        if key == "degrees":
            return quaternion_from_axis_degrees(axis, angle)  # exact at quarter turns
        return quat_from_axis_angle(axis, angle)
    unknown = sorted(str(k) for k in keys - {"quat", "axis", "degrees", "radians"})
    what = f"unknown key {unknown[0]!r}" if unknown else f"has keys {sorted(map(str, keys))}, which name no rotation"
    raise SceneError(where, what, hint)


def _join(values) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


#: The placement vocabulary of assembly parts and the command line, also taken for a body's pose:
#: scene key -> the key of the same thing it clashes with.
POSE_KEYS = {"translate": "position", "rotate": "rotation", "quat": "rotation", "rpy": "rotation"}


def pose(get: dict, place: str) -> tuple[np.ndarray, np.ndarray]:
    """The body frame's world position and orientation quaternion.

    ``position:`` and ``rotation:`` are the scene's own keys; ``translate:``, ``rotate:``,
    ``quat:`` and ``rpy:`` are the placement vocabulary of assembly parts and the command line,
    read by the same parser (``placement_from_mapping``) and taken as the body's pose.

    Parameters
    ----------
    get : dict
        The body's keys and values.
    place : str
        The body's place, for messages.
    """
    given = [k for k in POSE_KEYS if k in get]
    for key in given:
        own = POSE_KEYS[key]
        if own in get:
            raise SceneError(f"{place}.{key}", f"given with {own}:", f"give the body's {own} once")
    position = vector(get["position"], f"{place}.position") if "position" in get else np.zeros(3)
    orientation = rotation(get["rotation"], f"{place}.rotation") if "rotation" in get else np.array([1.0, 0, 0, 0])
    if not given:
        return position, orientation
    from p3d_cli.io.placements import placement_from_mapping
    from p3d_cli.geometry.rotation import matrix_quaternion

    try:
        placement = placement_from_mapping({k: get[k] for k in given}, place)
    except InputError as exc:
        raise SceneError(exc.where, exc.what, exc.hint) from None
    if placement.translation is not None:
        position = placement.translation
    if placement.rotation is not None:
        orientation = np.asarray(matrix_quaternion(placement.rotation), dtype=np.float64)
    return position, orientation


def pair(spec: dict, stem: str, place: str, body_a, body_b, point: bool):
    """``<stem>_a`` and ``<stem>_b`` of a constraint's entry, each in its body's frame (``body_a``
    and ``body_b`` are ``BodySpec``s); a missing one defaults to the other's world value,
    carried into its body's frame (the joint is assembled where the scene places it)."""
    key_a, key_b = f"{stem}_a", f"{stem}_b"
    given_a, given_b = spec.get(key_a) is not None, spec.get(key_b) is not None
    if not (given_a or given_b):
        raise SceneError(f"{place}.{key_a}", "missing",
                         f"give {key_a} and {key_b} (each in its own body's frame)")
    va = vector(spec[key_a], f"{place}.{key_a}", nonzero=not point) if given_a else None
    vb = vector(spec[key_b], f"{place}.{key_b}", nonzero=not point) if given_b else None
    ra, rb = quat_to_matrix(body_a.rotation), quat_to_matrix(body_b.rotation)
    with np.errstate(all="ignore"):     # an overflow is checked for just below
        if va is None:
            world = rb @ vb + (body_b.position if point else 0.0)
            va = ra.T @ (world - (body_a.position if point else 0.0))
        if vb is None:
            world = ra @ va + (body_a.position if point else 0.0)
            vb = rb.T @ (world - (body_b.position if point else 0.0))
    for key, v in ((key_a, va), (key_b, vb)):
        if not np.isfinite(v).all():
            raise SceneError(f"{place}.{key}", "carried into its body's frame, it overflows float64",
                             f"give {key} yourself, or positions nearer the origin")
    return va, vb
