"""Do two sheets of a surface cross along a line where their faces only touch?

A pair of faces can touch without crossing (``p3d_cli.mesh.triangle_pairs.CONTACT``) while the
surface around them crosses: an edge of one sheet lies in the plane of a face of another and
passes through its interior, with the edge's faces going one above and one below; or two sheets
meet along a common edge line (an edge used by four faces) and interleave. Whether they cross
is a property of the faces *around* the line, decided here exactly, in integer arithmetic
(these lines are rare: a few per mesh that has them). The coordinates are taken as integers on
one power-of-two grid (``IntegerPoints``): every sign below is of a polynomial homogeneous in
differences of points, so scaling every point by the same power of two keeps it, and Python's
integers do without the fractions' normalisations.

Around the line, each face that contains it is a half-plane, each one the boundary between
inside and outside: going round the line counter-clockwise, crossing a face whose normal points
the way one goes leaves the solid (winding number - 1), against it enters (+ 1). The winding
numbers of the sectors between the half-planes, up to a constant, follow. Two sheets that only
touch leave every sector within two consecutive values (0 and 1 for an outward solid: two
cubes side by side, a part resting on another); sheets that cross make one sector differ from
another by two or more (a region the divergence theorem counts twice or not at all). Faces
lying on each other count as one: two solids pressed face to face, or a flap of two opposite
faces (scans hold them), cancel; faces facing the same way (an overlap the pair test reports,
a duplicate the duplicate check reports) count once. A sheet that runs along another and then
passes through it shows where it leaves.
"""

from __future__ import annotations

import math
from functools import cmp_to_key

import numpy as np

from p3d_cli.geometry.rational import cross, dot, sign, sub


class IntegerPoints:
    """The points' coordinates as exact integers on one power-of-two grid: ``grid[v]`` is point
    ``v`` times ``2**-low`` (``[x, y, z]`` ints), with ``2**low`` the finest unit of any nonzero
    coordinate, made on first use."""

    def __init__(self, points: np.ndarray):
        self.points = np.asarray(points, dtype=np.float64)
        mantissa, exponent = np.frexp(self.points)
        used = exponent[mantissa != 0]
        self.low = int(used.min()) - 53 if used.size else 0
        self._rows: dict[int, list[int]] = {}

    def __getitem__(self, v: int) -> list[int]:
        row = self._rows.get(v)
        if row is None:
            row = self._rows[v] = [self._integer(x) for x in self.points[v].tolist()]
        return row

    def _integer(self, x: float) -> int:
        if x == 0:
            return 0
        mantissa, exponent = math.frexp(x)
        return int(mantissa * 2.0 ** 53) << (exponent - 53 - self.low)     # exact: 53 bits


class Line:
    """The oriented line through ``u`` and ``v`` (exact coordinates: ``IntegerPoints``' rows),
    and half-planes around it."""

    def __init__(self, u, v):
        self.u, self.v = list(u), list(v)
        self.along = sub(self.v, self.u)

    def turn(self, q0, q) -> int:
        """Where half-plane ``q`` lies from half-plane ``q0`` counter-clockwise about the line:
        0 (same angle), 1 (within a half turn), 2 (exactly opposite), 3 (beyond a half turn)."""
        r0, r = sub(q0, self.u), sub(q, self.u)
        side = sign(dot(cross(self.along, r0), r))
        if side > 0:
            return 1
        if side < 0:
            return 3
        # In the plane of the line and q0: the same half-plane or the opposite one.
        ll = dot(self.along, self.along)
        same = sign(ll * dot(r, r0) - dot(r, self.along) * dot(r0, self.along))
        return 0 if same > 0 else 2

    def order(self, q1, q2) -> int:
        """-1, 0, 1 as half-plane ``q1`` comes before, with or after ``q2`` (both within the
        same half turn from the reference)."""
        return -sign(dot(cross(self.along, sub(q1, self.u)), sub(q2, self.u)))

    def step(self, normal, q) -> int:
        """The winding change crossing half-plane ``q`` of a face with ``normal`` counter-clockwise."""
        moving = cross(self.along, sub(q, self.u))
        return -sign(dot(normal, moving))


def windings(line: Line, half_planes: list) -> list[tuple[int, int]]:
    """The half-planes ``(q, normal, face)`` in counter-clockwise order around ``line``, as
    ``(face, w)``: ``w`` the winding number (up to a constant) of the sector that follows.

    Faces lying on each other (half-planes at one angle) are one step, the sign of theirs
    added: a face and one facing it cancel (two solids pressed together, a flap of two
    opposite faces: nothing there), faces facing the same way count once (their overlap is
    the pair test's, their repetition the duplicate check's). Returns an empty list when the
    steps do not add up to zero (an open edge, or a surface not consistently oriented there:
    no winding number is defined).
    """
    if not half_planes:
        return []
    q0 = half_planes[0][0]
    keyed = [(line.turn(q0, q), q, line.step(normal, q), face) for q, normal, face in half_planes]

    def angle(x, y) -> int:
        if x[0] != y[0]:
            return -1 if x[0] < y[0] else 1
        return line.order(x[1], y[1]) if x[0] in (1, 3) else 0

    ordered = sorted(keyed, key=cmp_to_key(angle))
    groups: list[list] = []
    for item in ordered:
        if groups and angle(groups[-1][0], item) == 0:
            groups[-1].append(item)
        else:
            groups.append([item])
    steps = [(group[0][3], sign(sum(x[2] for x in group))) for group in groups]
    steps = [(face, step) for face, step in steps if step]
    if sum(step for _, step in steps) != 0:
        return []
    out, w = [], 0
    for face, step in steps:
        w += step
        out.append((face, w))
    return out


def crossing_faces(line: Line, half_planes: list) -> list[tuple[int, int]]:
    """The face pairs bounding the sectors of highest and lowest winding number when the
    sheets around ``line`` cross (their sectors span more than two consecutive winding
    numbers), else []."""
    w = windings(line, half_planes)
    if not w:
        return []
    values = [x for _, x in w]
    if max(values) - min(values) < 2:
        return []
    out = set()
    for target in (max(values), min(values)):
        k = values.index(target)
        a, b = w[k][0], w[(k + 1) % len(w)][0]
        if a != b:
            out.add((min(a, b), max(a, b)))
    return sorted(out)


def face_half_planes(points: IntegerPoints, faces: np.ndarray, face: int, line: Line) -> list:
    """The half-planes ``(q, normal, face)`` face ``face`` contributes around ``line`` (its
    points on ``line``'s grid): one if the line runs along one of its edges, two if it crosses
    its interior (a vertex on each side)."""
    corners = [points[int(v)] for v in faces[face]]
    normal = cross(sub(corners[1], corners[0]), sub(corners[2], corners[0]))
    off = [c for c in corners if any(cross(line.along, sub(c, line.u)))]
    if len(off) == 1:
        return [(off[0], normal, face)]
    sides: dict[int, list] = {}
    for c in off:
        sides.setdefault(sign(dot(cross(line.along, sub(c, line.u)), normal)), []).append(c)
    return [(group[0], normal, face) for group in sides.values()]
