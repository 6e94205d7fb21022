"""Rotations: from an axis and an angle in degrees, from a quaternion, and composed.

This is the one module of rotation maths: ``--rotate``/``--quat``, shape placement and the
constraint solver's body orientations all use these functions.

Convention (stated in ``p3d bounds --help`` and docs/shapes.md): rotations are active and
about the world origin, ``x -> R x``. Repeated turns are each applied after the previous one
about the world (fixed) axes, so ``--rotate z:90 --rotate x:90`` gives ``R = R_x R_z``; in
general ``R = R_n ... R_2 R_1``. A turn by a positive angle is counter-clockwise looking down
the axis towards the origin (right-hand rule). A quaternion ``w + xi + yj + zk`` is normalised
first; ``q`` and ``-q`` give the same rotation.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from p3d_cli.errors import UsageError

#: Named axes accepted by ``--rotate``.
AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def cos_sin_degrees(degrees: float) -> tuple[float, float]:
    """``cos`` and ``sin`` of an angle in degrees, exact at multiples of 90°.

    ``math.cos(math.radians(90))`` is 6e-17, not 0; reducing the angle to [-45°, 45°] about
    the nearest quarter turn first makes quarter turns exact (so a box turned by 90° keeps
    exact bounds) and keeps the rest accurate. The angle is first reduced modulo 360° with
    ``math.fmod``, which is exact for every float: 1e20° is 280°, not a rounding of 1e20/90
    quarter turns (which would be the identity).
    """
    degrees = math.fmod(degrees, 360.0)
    quarter = round(degrees / 90.0)
    rest_degrees = degrees - 90.0 * quarter
    rest = math.radians(rest_degrees)
    c, s = math.cos(rest), math.sin(rest)
    if abs(rest_degrees) == 45.0:
        # cos(π/4) and sin(π/4) round to neighbouring floats; equal components make the
        # half-angle quaternion of a quarter turn give an exact matrix (quaternion_matrix).
        c, s = math.sqrt(0.5), math.copysign(math.sqrt(0.5), rest_degrees)
    for _ in range(quarter % 4):
        c, s = -s, c          # add 90°: cos(a+90) = -sin a, sin(a+90) = cos a
    return c, s


def rotation_from_axis_degrees(axis, degrees: float) -> np.ndarray:
    """The rotation by ``degrees`` about ``axis`` (right-hand rule), ``(3, 3) float64``.

    Parameters
    ----------
    axis : {"x", "y", "z"} or (3,) array_like
        A named axis or a direction (normalised here).
    degrees : float

    Raises
    ------
    UsageError
        Unknown axis name, zero or non-finite axis vector, non-finite angle.
    """
    u = _unit_axis(axis, degrees)
    c, s = cos_sin_degrees(degrees)
    # Rodrigues: R = c E + s [u]x + (1 - c) u uᵀ.
    ux = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    return c * np.eye(3) + s * ux + (1.0 - c) * np.outer(u, u)


def _unit_axis(axis, degrees: float) -> np.ndarray:
    """The unit vector of a named axis or a direction, checking the angle is finite too."""
    if isinstance(axis, str):
        if axis.lower() not in AXES:
            raise UsageError("rotate", f"unknown axis {axis!r}", "use x, y, z or a vector such as 1,1,0")
        u = np.array(AXES[axis.lower()])
    else:
        u = np.asarray(axis, dtype=np.float64).reshape(3)
    norm = float(np.linalg.norm(u))
    if not math.isfinite(norm) or norm == 0.0:
        raise UsageError("rotate", f"axis {tuple(float(x) for x in u)} has no direction",
                         "give a non-zero axis vector such as 1,1,0")
    if not math.isfinite(degrees):
        raise UsageError("rotate", f"angle {degrees!r} is not finite", "give the angle in degrees")
    return u / norm


# Each entry of R(q), times |q|², is a sum of two products q_i q_j (times ±1 or ±2): a constant
# linear map of the outer product q qᵀ (entry q_i q_j at 4 i + j), so (n, 3, 3) matrices are one
# outer product and one matrix product, the form stepping's inner loop needs.
_QQ_TO_R = np.zeros((16, 9))
for _entry, _terms in enumerate((((0, 1), (5, 1), (10, -1), (15, -1)), ((6, 2), (3, -2)), ((7, 2), (2, 2)),
                                 ((6, 2), (3, 2)), ((0, 1), (5, -1), (10, 1), (15, -1)), ((11, 2), (1, -2)),
                                 ((7, 2), (2, -2)), ((11, 2), (1, 2)), ((0, 1), (5, -1), (10, -1), (15, 1)))):
    for _k, _weight in _terms:
        _QQ_TO_R[_k, _entry] = _weight


def quaternion_matrix(q) -> np.ndarray:
    """Rotation matrix of quaternions ``[w, x, y, z]``: the one copy of this formula.

    The homogeneous form ``R = (1/|q|²) [[w²+x²-y²-z², 2(xy-wz), 2(xz+wy)], ...]`` is used rather
    than ``1 - 2(y² + z²)``: it is exact at quarter turns whose quaternion has equal components
    (90° about z is ``(√½, 0, 0, √½)``: ``w² - z²`` is exactly 0 and ``2wz / |q|²`` exactly 1,
    where ``1 - 2z²`` gives 2e-16), and it needs no unit length.

    Parameters
    ----------
    q : (4,) or (..., 4) array_like of float
        Not zero (callers that take user input refuse the zero quaternion first).

    Returns
    -------
    (3, 3) or (..., 3, 3) float64
    """
    q = np.asarray(q, dtype=np.float64)
    flat = q.reshape(-1, 4)
    qq = (flat[:, :, None] * flat[:, None, :]).reshape(-1, 16)
    norm = qq[:, 0] + qq[:, 5] + qq[:, 10] + qq[:, 15]
    return ((qq @ _QQ_TO_R) / norm[:, None]).reshape(q.shape[:-1] + (3, 3))


def quaternion_from_axis_degrees(axis, degrees: float) -> np.ndarray:
    """The unit quaternion ``[w, x, y, z]`` of a turn by ``degrees`` about ``axis``.

    Built from ``cos_sin_degrees(degrees / 2)``, so a quarter turn's quaternion has exactly equal
    components and ``quaternion_matrix`` gives the same exact matrix as
    ``rotation_from_axis_degrees``.

    Raises
    ------
    UsageError
        As ``rotation_from_axis_degrees``.
    """
    u = _unit_axis(axis, degrees)
    c, s = cos_sin_degrees(degrees / 2.0)
    return np.concatenate([[c], s * u])


def rotation_from_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    """The rotation of the unit quaternion ``(w, x, y, z) / |q|``, ``(3, 3) float64``.

    Raises
    ------
    UsageError
        The quaternion is zero or not finite.
    """
    q = np.array([w, x, y, z], dtype=np.float64)
    norm = float(np.linalg.norm(q))
    if not math.isfinite(norm):
        raise UsageError("quat", f"{tuple(q.tolist())} is not finite", "give four finite numbers W,X,Y,Z")
    if norm == 0.0:
        raise UsageError("quat", "the zero quaternion is no rotation",
                         "give W,X,Y,Z not all zero (1,0,0,0 is the identity)")
    return quaternion_matrix(q / norm)


def compose_rotations(rotations: Iterable[np.ndarray]) -> np.ndarray:
    """``R_n ... R_2 R_1``: each rotation applied after the previous, about the world axes."""
    total = np.eye(3)
    for r in rotations:
        total = np.asarray(r, dtype=np.float64) @ total
    return total


def parse_turn(text: str) -> np.ndarray:
    """The rotation of one ``AXIS:DEGREES`` turn (``z:90``, ``1,1,0:-30``).

    Raises
    ------
    UsageError
        Not of that form.
    """
    hint = "write AXIS:DEGREES with AXIS x, y, z or a vector, e.g. z:90 or 1,1,0:45"
    axis_text, sep, angle_text = str(text).rpartition(":")
    if not sep or not axis_text.strip():
        raise UsageError("rotate", f"{text!r} has no axis", hint)
    try:
        degrees = float(angle_text)
    except ValueError:
        raise UsageError("rotate", f"angle {angle_text!r} is not a number", hint) from None
    axis_text = axis_text.strip()
    if axis_text.lower() in AXES:
        return rotation_from_axis_degrees(axis_text, degrees)
    try:
        axis = [float(p) for p in axis_text.split(",")]
    except ValueError:
        raise UsageError("rotate", f"axis {axis_text!r} is neither x, y, z nor a vector", hint) from None
    if len(axis) != 3:
        raise UsageError("rotate", f"axis {axis_text!r} needs three components", hint)
    return rotation_from_axis_degrees(axis, degrees)


def parse_quaternion(text: str) -> np.ndarray:
    """The rotation of ``W,X,Y,Z`` text (normalised); ``UsageError`` when malformed."""
    hint = "write --quat W,X,Y,Z (scalar first), e.g. --quat 0.7071,0,0,0.7071 for 90° about z"
    return rotation_from_quaternion(*_numbers(text, 4, "quat", hint))


def _numbers(text: str, count: int, parameter: str, hint: str) -> list[float]:
    """``count`` comma-separated numbers of ``text``; ``UsageError`` naming ``parameter`` else."""
    words = {3: "three", 4: "four"}.get(count, str(count))
    try:
        values = [float(p) for p in str(text).split(",")]
    except ValueError:
        raise UsageError(parameter, f"{text!r} is not {words} numbers", hint) from None
    if len(values) != count:
        raise UsageError(parameter, f"{text!r} has {len(values)} numbers, not {count}", hint)
    return values


def rotation_from_rpy(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """The rotation of URDF roll-pitch-yaw angles (radians), ``(3, 3) float64``.

    URDF's convention (``<origin rpy="r p y"/>``): turns about the fixed world axes, first
    ``roll`` about x, then ``pitch`` about y, then ``yaw`` about z, so ``R = Rz(y) Ry(p) Rx(r)``
    (ROS REP 103; the same matrix as intrinsic z-y'-x'' turns by yaw, pitch, roll).

    Raises
    ------
    UsageError
        An angle is not finite.
    """
    angles = (roll, pitch, yaw)
    if not all(math.isfinite(a) for a in angles):
        raise UsageError("rpy", f"{angles} is not three finite angles", "give roll, pitch, yaw in radians")
    (cr, sr), (cp, sp), (cy, sy) = ((math.cos(a), math.sin(a)) for a in angles)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return compose_rotations((rx, ry, rz))


def parse_rpy(text: str) -> np.ndarray:
    """The rotation of ``R,P,Y`` text (radians, URDF convention); ``UsageError`` when malformed."""
    hint = "write R,P,Y in radians (roll about x, then pitch about y, then yaw about z, fixed axes)"
    return rotation_from_rpy(*_numbers(text, 3, "rpy", hint))


def matrix_quaternion(rotation) -> np.ndarray:
    """The unit quaternion ``[w, x, y, z]`` of a proper rotation matrix, with ``w >= 0``.

    Shepperd's method (J. Guidance and Control 1(3), 1978): of ``4w², 4x², 4y², 4z²`` (each a
    sum of diagonal entries) take the largest, whose square root is far from zero, and get
    the other three from the off-diagonal sums and differences divided by it. This avoids
    the cancellation of ``w = sqrt(1 + tr R) / 2`` near half turns. The inverse of
    ``quaternion_matrix``: ``quaternion_matrix(matrix_quaternion(R)) == R`` to rounding.
    MJCF's ``quat`` attribute takes this order (scalar first).

    Parameters
    ----------
    rotation : (3, 3) array_like
        A rotation (orthonormal, determinant +1).
    """
    r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    squares = np.array([1 + r[0, 0] + r[1, 1] + r[2, 2], 1 + r[0, 0] - r[1, 1] - r[2, 2],
                        1 - r[0, 0] + r[1, 1] - r[2, 2], 1 - r[0, 0] - r[1, 1] + r[2, 2]])
    k = int(np.argmax(squares))
    big = 0.5 * math.sqrt(max(float(squares[k]), 0.0))
    f = 0.25 / big
    if k == 0:
        q = [big, (r[2, 1] - r[1, 2]) * f, (r[0, 2] - r[2, 0]) * f, (r[1, 0] - r[0, 1]) * f]
    elif k == 1:
        q = [(r[2, 1] - r[1, 2]) * f, big, (r[0, 1] + r[1, 0]) * f, (r[0, 2] + r[2, 0]) * f]
    elif k == 2:
        q = [(r[0, 2] - r[2, 0]) * f, (r[0, 1] + r[1, 0]) * f, big, (r[1, 2] + r[2, 1]) * f]
    else:
        q = [(r[1, 0] - r[0, 1]) * f, (r[0, 2] + r[2, 0]) * f, (r[1, 2] + r[2, 1]) * f, big]
    out = np.array(q)
    out /= np.linalg.norm(out)
    return (-out if out[0] < 0 else out) + 0.0


def matrix_rpy(rotation) -> np.ndarray:
    """URDF roll, pitch, yaw (radians) of a proper rotation: ``rotation_from_rpy(*rpy) == R``.

    ``R = Rz(y) Ry(p) Rx(r)`` has ``R[2, 0] = -sin p``, ``R[2, 1] = cos p sin r``,
    ``R[2, 2] = cos p cos r``, ``R[1, 0] = sin y cos p``, ``R[0, 0] = cos y cos p``; pitch is
    taken in [-π/2, π/2]. At gimbal lock (``cos p = 0``) only ``y - r`` (or ``y + r``) is
    determined: roll is set to 0 and yaw takes the whole turn.
    """
    r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    cos_pitch = math.hypot(r[0, 0], r[1, 0])
    pitch = math.atan2(-r[2, 0], cos_pitch)
    if cos_pitch > 1e-12:
        roll = math.atan2(r[2, 1], r[2, 2])
        yaw = math.atan2(r[1, 0], r[0, 0])
    else:
        # Gimbal lock: R = Rz(y) Ry(±π/2) Rx(r) depends on y ∓ r alone; with r = 0,
        # R[0, 1] = -sin y and R[1, 1] = cos y.
        roll = 0.0
        yaw = math.atan2(-r[0, 1], r[1, 1])
    return np.array([roll, pitch, yaw]) + 0.0
