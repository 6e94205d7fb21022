"""The kinematics of a small scene's step in plain Python floats.

For a scene of a few bodies, a numpy call (~1 µs of overhead on arrays of 3-20 numbers) costs
more than the arithmetic it does: a quaternion update is ~50 float operations, ~2 µs in Python
and ~15 µs as a dozen numpy calls. ``small_step`` therefore keeps a small scene's state as lists
of floats and does everything per body and per constraint here, leaving numpy only the
island-sized linear algebra. The formulas are those of ``rotation``, ``rows`` and the constraint
modules (``ball``, ``hinge``, ``bar``), in the same order of operations where that is cheap, so
results agree with the array code to rounding (~1e-16 relative).

Vectors are tuples or lists of 3 floats, matrices 9 floats row-major, quaternions ``[w, x, y, z]``.
"""

from __future__ import annotations

import math

from p3d_cli.constraints.rows import bar_met_error


def rotate(q, rx: float, ry: float, rz: float) -> tuple[float, float, float, float]:
    """``exp(θ) ⊗ q`` renormalised (``rotation.rotate_by_many`` for one body)."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    half = 0.5 * angle
    # sin(|θ|/2)/|θ|, through its series below 1e-8 so that tiny rotations stay exact.
    factor = math.sin(half) / angle if angle >= 1e-8 else 0.5 - angle * angle / 48.0
    pw, px, py, pz = math.cos(half), factor * rx, factor * ry, factor * rz
    qw, qx, qy, qz = q
    w = pw * qw - px * qx - py * qy - pz * qz
    x = pw * qx + px * qw + py * qz - pz * qy
    y = pw * qy - px * qz + py * qw + pz * qx
    z = pw * qz + px * qy - py * qx + pz * qw
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    return w / norm, x / norm, y / norm, z / norm


def matrix(q) -> list[float]:
    """Rotation matrix of ``q`` in the homogeneous form of ``p3d_cli.rotation.quaternion_matrix``
    (exact at quarter turns, no unit length needed)."""
    w, x, y, z = q
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    n = ww + xx + yy + zz
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    return [(ww + xx - yy - zz) / n, (2 * xy - 2 * wz) / n, (2 * xz + 2 * wy) / n,
            (2 * xy + 2 * wz) / n, (ww - xx + yy - zz) / n, (2 * yz - 2 * wx) / n,
            (2 * xz - 2 * wy) / n, (2 * yz + 2 * wx) / n, (ww - xx - yy + zz) / n]


def apply(r, v) -> tuple[float, float, float]:
    """``R v`` for a row-major 3×3 ``r``."""
    v0, v1, v2 = v
    return (r[0] * v0 + r[1] * v1 + r[2] * v2, r[3] * v0 + r[4] * v1 + r[5] * v2,
            r[6] * v0 + r[7] * v1 + r[8] * v2)


def apply_t(r, v) -> tuple[float, float, float]:
    """``Rᵀ v``."""
    v0, v1, v2 = v
    return (r[0] * v0 + r[3] * v1 + r[6] * v2, r[1] * v0 + r[4] * v1 + r[7] * v2,
            r[2] * v0 + r[5] * v1 + r[8] * v2)


def conjugate(r, m) -> list[float]:
    """``R M Rᵀ`` for a symmetric ``M`` (a world inverse inertia), symmetric by construction."""
    a = [r[0] * m[0] + r[1] * m[3] + r[2] * m[6], r[0] * m[1] + r[1] * m[4] + r[2] * m[7],
         r[0] * m[2] + r[1] * m[5] + r[2] * m[8],
         r[3] * m[0] + r[4] * m[3] + r[5] * m[6], r[3] * m[1] + r[4] * m[4] + r[5] * m[7],
         r[3] * m[2] + r[4] * m[5] + r[5] * m[8],
         r[6] * m[0] + r[7] * m[3] + r[8] * m[6], r[6] * m[1] + r[7] * m[4] + r[8] * m[7],
         r[6] * m[2] + r[7] * m[5] + r[8] * m[8]]
    xx = a[0] * r[0] + a[1] * r[1] + a[2] * r[2]
    xy = a[0] * r[3] + a[1] * r[4] + a[2] * r[5]
    xz = a[0] * r[6] + a[1] * r[7] + a[2] * r[8]
    yy = a[3] * r[3] + a[4] * r[4] + a[5] * r[5]
    yz = a[3] * r[6] + a[4] * r[7] + a[5] * r[8]
    zz = a[6] * r[6] + a[7] * r[7] + a[8] * r[8]
    return [xx, xy, xz, xy, yy, yz, xz, yz, zz]


def cross(a, b) -> tuple[float, float, float]:
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


def hinge_frame(za, zb):
    """``(x, y, s)`` of ``rows.hinge_frames`` for one hinge: ``z`` the bisector of the world axes
    (``zb`` flipped by ``s`` when it points away), ``x`` the world axis least aligned with ``z``
    (the first on a tie, as ``numpy.argmin``) made perpendicular, ``y = z × x``."""
    s = 1.0 if za[0] * zb[0] + za[1] * zb[1] + za[2] * zb[2] >= 0 else -1.0
    z0, z1, z2 = za[0] + s * zb[0], za[1] + s * zb[1], za[2] + s * zb[2]
    norm = math.sqrt(z0 * z0 + z1 * z1 + z2 * z2)
    z = (z0 / norm, z1 / norm, z2 / norm)
    a0, a1, a2 = abs(z[0]), abs(z[1]), abs(z[2])
    pick = 0 if (a0 <= a1 and a0 <= a2) else (1 if a1 <= a2 else 2)
    zp = z[pick]
    x = [-zp * z[0], -zp * z[1], -zp * z[2]]
    x[pick] = 1.0 - zp * z[pick]
    norm = math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2])
    x = (x[0] / norm, x[1] / norm, x[2] / norm)
    return x, cross(z, x), s


class Joint:
    """One constraint's constants and its per-configuration evaluation.

    ``evaluate`` returns the position errors (``rows.RowSet.errors`` for this constraint) and
    keeps what ``entries`` (the variable entries of its rows) needs.
    """

    __slots__ = ("kind", "a", "b", "off_a", "off_b", "axis_a", "axis_b", "length", "where", "_state")

    def __init__(self, kind, a, b, off_a, off_b, axis_a, axis_b, length, where) -> None:
        self.kind, self.a, self.b = kind, a, b
        self.off_a, self.off_b, self.axis_a, self.axis_b = off_a, off_b, axis_a, axis_b
        self.length, self.where = length, where
        self._state: tuple = ()

    def evaluate(self, com, rot) -> list[float]:
        """Position errors at centres of mass ``com`` (flat, 3 per body) and rotations ``rot``."""
        a, b = self.a, self.b
        ra, rb = apply(rot[a], self.off_a), apply(rot[b], self.off_b)
        gap = ((com[3 * b] + rb[0]) - (com[3 * a] + ra[0]), (com[3 * b + 1] + rb[1]) - (com[3 * a + 1] + ra[1]),
               (com[3 * b + 2] + rb[2]) - (com[3 * a + 2] + ra[2]))
        if self.kind == "ball":
            self._state = (ra, rb)
            return list(gap)
        if self.kind == "bar":
            norm = math.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])
            self._state = (ra, rb, gap, norm)
            return [norm - self.length]
        za, zb = apply(rot[a], self.axis_a), apply(rot[b], self.axis_b)
        x, y, s = hinge_frame(za, zb)
        tilt = cross(za, (s * zb[0], s * zb[1], s * zb[2]))
        self._state = (ra, rb, x, y)
        return [gap[0], gap[1], gap[2], tilt[0] * x[0] + tilt[1] * x[1] + tilt[2] * x[2],
                tilt[0] * y[0] + tilt[1] * y[1] + tilt[2] * y[2]]

    def entries(self, free_a: bool, free_b: bool) -> list[float]:
        """The entries of its rows that depend on the pose, side a's then side b's (free sides
        only), in the order ``small_step`` scatters them (the ``±E`` entries are constant)."""
        out: list[float] = []
        if self.kind == "bar":
            ra, rb, gap, norm = self._state
            if norm == 0.0:
                raise bar_met_error(self.where)
            d = (gap[0] / norm, gap[1] / norm, gap[2] / norm)
            if free_a:
                ca = cross(ra, d)
                out += [-d[0], -d[1], -d[2], -ca[0], -ca[1], -ca[2]]
            if free_b:
                out += [*d, *cross(rb, d)]
            return out
        ra, rb = self._state[0], self._state[1]
        # Ball rows (a hinge's first three): [-E, [r_a]ₓ] and [E, -[r_b]ₓ]; a hinge's axis rows
        # [0, -x], [0, -y] and [0, x], [0, y].
        if free_a:
            out += [0.0, -ra[2], ra[1], ra[2], 0.0, -ra[0], -ra[1], ra[0], 0.0]
            if self.kind == "hinge":
                x, y = self._state[2], self._state[3]
                out += [-x[0], -x[1], -x[2], -y[0], -y[1], -y[2]]
        if free_b:
            out += [0.0, rb[2], -rb[1], -rb[2], 0.0, rb[0], rb[1], -rb[0], 0.0]
            if self.kind == "hinge":
                out += [*self._state[2], *self._state[3]]
        return out

    def columns(self) -> list[tuple[int, int]]:
        """(local row, column within a side's 6) of ``entries``' values for one side, in order."""
        if self.kind == "bar":
            return [(0, j) for j in range(6)]
        out = [(i, 3 + j) for i in range(3) for j in range(3)]
        if self.kind == "hinge":
            out += [(3 + i, 3 + j) for i in range(2) for j in range(3)]
        return out
