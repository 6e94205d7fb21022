"""Every constraint's rows at once: the arrays of one scene, prepared once, evaluated per step.

``ball``, ``hinge`` and ``bar`` define each constraint type one constraint at a time, which is
the clearest statement of its equations and what reporting uses. Stepping evaluates the same
equations thousands of times, where a Python loop over constraints costs far more than the
arithmetic; ``RowSet`` holds the per-scene constants (body indices, attachment offsets from the
centres of mass, axes, lengths, where each row goes) as arrays, so that one evaluation is a
fixed handful of numpy calls whatever the number of constraints.

Rows are in scene order: constraint 0's rows, then constraint 1's, and within a constraint in
the order of its module (ball: the gap x, y, z; hinge: the gap, then the axis rows along
``x`` and ``y``; bar: one row). The formulas are those of the modules, written over arrays.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.constraints.registry import CONSTRAINT_TYPES
from p3d_cli.errors import SceneError


class Geometry:
    """World geometry of every constraint at one instant (arrays over constraints).

    Attributes
    ----------
    r_a, r_b : (c, 3) float64
        Attachment points minus centres of mass, world frame.
    gap : (c, 3) float64
        ``p_b - p_a``, the attachment points' separation.
    z_a, z_b : (h, 3) float64
        World hinge axes of the hinges (in the order of ``RowSet.hinges``).
    """

    __slots__ = ("r_a", "r_b", "gap", "z_a", "z_b", "_frames")

    def __init__(self, r_a, r_b, gap, z_a, z_b) -> None:
        self.r_a, self.r_b, self.gap, self.z_a, self.z_b = r_a, r_b, gap, z_a, z_b
        self._frames = None

    def frames(self):
        """``hinge_frames`` of the hinges, computed once (errors and rows both need them)."""
        if self._frames is None:
            self._frames = hinge_frames(self.z_a, self.z_b)
        return self._frames


class RowSet:
    """The constraint rows of one scene.

    Parameters
    ----------
    scene : Scene
    index : dict
        Body name -> index in the world arrays.
    com_body : (n, 3) float64
        Centres of mass in the body frames.

    Attributes
    ----------
    a, b : (c,) int
        Body indices of each constraint.
    row_a, row_b : (m,) int
        Body indices of each row's two sides.
    row_constraint : (m,) int
        Constraint of each row.
    offsets : (c + 1,) int
        First row of each constraint.
    """

    def __init__(self, scene, index: dict, com_body: np.ndarray) -> None:
        specs = scene.constraints
        self.where = [c.where for c in specs]
        self.a = np.array([index[c.a] for c in specs], dtype=np.intp)
        self.b = np.array([index[c.b] for c in specs], dtype=np.intp)
        sizes = np.array([CONSTRAINT_TYPES[c.type].EQUATIONS for c in specs], dtype=np.intp)
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
        self.m = int(self.offsets[-1])
        self.row_constraint = np.repeat(np.arange(len(specs)), sizes)
        self.row_a, self.row_b = self.a[self.row_constraint], self.b[self.row_constraint]
        # Attachment offsets from the centres of mass, body frames: constant for the scene.
        self.off_a = np.array([c.attach_a for c in specs]).reshape(-1, 3) - com_body[self.a]
        self.off_b = np.array([c.attach_b for c in specs]).reshape(-1, 3) - com_body[self.b]
        kinds = [c.type for c in specs]
        self.balls = np.array([k for k, t in enumerate(kinds) if t == "ball"], dtype=np.intp)
        self.hinges = np.array([k for k, t in enumerate(kinds) if t == "hinge"], dtype=np.intp)
        self.bars = np.array([k for k, t in enumerate(kinds) if t == "bar"], dtype=np.intp)
        # Rows of each type, so that per-type results land in scene order in one assignment.
        self.gap_rows = self.offsets[np.concatenate([self.balls, self.hinges])][:, None] + np.arange(3)
        self.gap_of = np.concatenate([self.balls, self.hinges])
        self.axis_rows = self.offsets[self.hinges][:, None] + np.array([3, 4])
        self.bar_rows = self.offsets[self.bars]
        self.axis_a = np.array([specs[k].axis_a for k in self.hinges]).reshape(-1, 3)
        self.axis_b = np.array([specs[k].axis_b for k in self.hinges]).reshape(-1, 3)
        self.length = np.array([specs[k].length for k in self.bars], dtype=np.float64)
        self.rot_index = np.concatenate([self.a, self.b, self.a[self.hinges], self.b[self.hinges]])
        self.com_index = np.concatenate([self.a, self.b])
        self.body_vectors = np.concatenate([self.off_a, self.off_b, self.axis_a, self.axis_b])[:, :, None]
        # The constant entries of the rows (±E of the ball rows) and where [r]ₓ goes.
        self.template_a, self.template_b = np.zeros((self.m, 6)), np.zeros((self.m, 6))
        self.template_a[self.gap_rows, np.arange(3)] = -1.0
        self.template_b[self.gap_rows, np.arange(3)] = 1.0
        self.gap_rows_flat = self.gap_rows.ravel()
        self.bar_where = [self.where[k] for k in self.bars]

    def geometry(self, com: np.ndarray, rot: np.ndarray) -> Geometry:
        """World geometry at centres of mass ``com`` (n, 3) and rotations ``rot`` (n, 3, 3)."""
        c, h = len(self.a), len(self.hinges)
        # Every body-frame vector (attachment offsets, then hinge axes) turned in one product.
        v = (rot[self.rot_index] @ self.body_vectors)[:, :, 0]
        p = com[self.com_index] + v[:2 * c]
        return Geometry(v[:c], v[c:2 * c], p[c:] - p[:c], v[2 * c:2 * c + h], v[2 * c + h:])

    def errors(self, geo: Geometry) -> np.ndarray:
        """(m,) position equations ``C``, scene row order (the modules' ``position_error``)."""
        out = np.empty(self.m)
        if len(self.gap_of):
            out[self.gap_rows] = geo.gap[self.gap_of]
        if len(self.hinges):
            x, y, _, s = geo.frames()
            tilt = cross_rows(geo.z_a, s[:, None] * geo.z_b)
            out[self.axis_rows[:, 0]] = (tilt * x).sum(axis=1)
            out[self.axis_rows[:, 1]] = (tilt * y).sum(axis=1)
        if len(self.bars):
            gap = geo.gap[self.bars]
            out[self.bar_rows] = np.sqrt((gap * gap).sum(axis=1)) - self.length
        return out

    def jacobian(self, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        """``(JA, JB)``, each (m, 6): row ``i`` is ``JA[i] · u[row_a[i]] + JB[i] · u[row_b[i]]``."""
        ja, jb = self.template_a.copy(), self.template_b.copy()
        g, rows = self.gap_of, self.gap_rows_flat
        if len(g):
            # Ball rows (also a hinge's first three): [-E, [r_a]ₓ] and [E, -[r_b]ₓ].
            ja[rows, 3:] = (geo.r_a[g][:, _SKEW_PICK] * _SKEW_SIGN).reshape(-1, 3)
            jb[rows, 3:] = (geo.r_b[g][:, _SKEW_PICK] * -_SKEW_SIGN).reshape(-1, 3)
        if len(self.hinges):
            x, y, _, _ = geo.frames()
            ja[self.axis_rows[:, 0], 3:], jb[self.axis_rows[:, 0], 3:] = -x, x
            ja[self.axis_rows[:, 1], 3:], jb[self.axis_rows[:, 1], 3:] = -y, y
        if len(self.bars):
            d = bar_directions(geo.gap[self.bars], self.bar_where)
            rows = self.bar_rows
            ja[rows, :3], jb[rows, :3] = -d, d
            ja[rows, 3:] = -cross_rows(geo.r_a[self.bars], d)
            jb[rows, 3:] = cross_rows(geo.r_b[self.bars], d)
        return ja, jb

    def apply(self, ja: np.ndarray, jb: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(m,) ``J u`` for body motions ``u`` (n, 6)."""
        return (ja * u[self.row_a] + jb * u[self.row_b]).sum(axis=1)


#: ``[r]ₓ`` row-major as ``r[_SKEW_PICK] * _SKEW_SIGN`` (``rotation.skew``).
_SKEW_PICK = np.array([0, 2, 1, 2, 0, 0, 1, 0, 0])
_SKEW_SIGN = np.array([0.0, -1, 1, 1, 0, -1, -1, 1, 0])


def hinge_frames(z_a: np.ndarray, z_b: np.ndarray):
    """``(x, y, z, s)`` of ``hinge.frame`` for (h, 3) axis pairs: ``z`` the bisector of the axes
    (``z_b`` flipped by ``s`` when it points away), ``x`` the world axis least aligned with
    ``z`` made perpendicular, ``y = z × x``."""
    s = np.where((z_a * z_b).sum(axis=1) >= 0, 1.0, -1.0)
    z = z_a + s[:, None] * z_b
    # Unit axes with z_a · s z_b >= 0 give |z|² = 2 + 2|z_a · z_b| >= 2: never zero.
    z /= np.sqrt((z * z).sum(axis=1))[:, None]
    pick = np.argmin(np.abs(z), axis=1)
    # x = e_pick - z_pick z, the seed axis made perpendicular (as hinge.frame computes it).
    x = _EYE[pick] - z.ravel()[3 * np.arange(len(z)) + pick][:, None] * z
    x /= np.sqrt((x * x).sum(axis=1))[:, None]
    return x, cross_rows(z, x), z, s


_EYE = np.eye(3)
_NEXT, _LAST = np.array([1, 2, 0]), np.array([2, 0, 1])


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` row by row for (c, 3) arrays, in few numpy calls."""
    return a[:, _NEXT] * b[:, _LAST] - a[:, _LAST] * b[:, _NEXT]


def bar_directions(gap: np.ndarray, where) -> np.ndarray:
    """Unit vectors along (b, 3) bar gaps; a bar whose points met is one ``SceneError``."""
    norm = np.sqrt((gap * gap).sum(axis=1))
    if not norm.all():
        raise bar_met_error(where[int(np.flatnonzero(norm == 0.0)[0])])
    return gap / norm[:, None]


def bar_met_error(where: str) -> SceneError:
    """The error of a bar whose attachment points have met (it has no direction)."""
    return SceneError(where or "bar", "the attachment points have come together, so the bar has "
                      "no direction", "use a ball joint to join two points, or a smaller --dt")
