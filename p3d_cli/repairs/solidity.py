"""What repair takes from ``p3d check``'s exact solidity tests: orientation signs, vertex
welding, the nesting of closed shells and self-intersections.

These come from the self-intersection work (``p3d_cli.geometry.predicates``,
``p3d_cli.mesh.weld``, ``p3d_cli.mesh.nesting``, ``p3d_cli.mesh.intersections``). This module
is the one place repair reaches them, so that every step names what it needs in one vocabulary:

- ``orient2d(a, b, c, safe)``: exact signs of 2-D orientations (the hole triangulation);
- ``weld_points(points, tolerance)``: which vertex each vertex merges into (``weld``);
- ``nesting_depths(points, faces, labels, closed)``: how many closed shells lie around each
  closed shell (``outward``: a shell inside an odd number of others is a cavity);
- ``new_face_crossings(points, faces, new)``: new faces whose interiors cross or overlap other
  faces (a filled hole must add no self-intersection);
- ``self_intersections(points, faces)``: every crossing pair, for the report of what repair
  cannot fix.

A test that this build of p3d lacks raises ``Unavailable``; the step that needed it says so in
its report and leaves the mesh as it was, and the repair is not called fixed when the test
was needed to call it so.
"""

from __future__ import annotations

import importlib
from fractions import Fraction

import numpy as np


class Unavailable(Exception):
    """A test this build of p3d does not have (its module is missing)."""


def _module(name: str):
    try:
        return importlib.import_module(name)
    except ImportError:
        raise Unavailable(name) from None


def available(name: str) -> bool:
    """Whether the module ``name`` (``p3d_cli.mesh.nesting``, ...) is part of this build."""
    try:
        _module(name)
    except Unavailable:
        return False
    return True


# ---------------------------------------------------------------------------------------------
# Exact orientation signs.
#
# ``p3d_cli.geometry.predicates`` (Shewchuk's filter with its proven bound, then integers) when
# present; until then the same stage-A filter as ``p3d_cli.mesh.faces`` with an exact
# ``Fraction`` fallback for the rows it cannot decide (exact either way, only slower).
# ---------------------------------------------------------------------------------------------

_EPS = 2.0 ** -53
_CCW_BOUND = (3.0 + 16.0 * _EPS) * _EPS


def in_safe_range(points: np.ndarray) -> bool:
    """Whether every nonzero coordinate's magnitude lies in ``[2**-200, 2**200]`` (the
    filter's products stay normal floats)."""
    try:
        return bool(_module("p3d_cli.geometry.predicates").in_safe_range(points))
    except Unavailable:
        magnitude = np.abs(np.asarray(points, dtype=np.float64))
        if magnitude.size == 0:
            return True
        nonzero = magnitude[magnitude != 0]
        return bool(float(magnitude.max()) <= 2.0 ** 200 and (nonzero.size == 0 or float(nonzero.min()) >= 2.0 ** -200))


def orient2d(a: np.ndarray, b: np.ndarray, c: np.ndarray, safe: bool = True) -> np.ndarray:
    """Exact signs ``(k,)`` int8 of ``(b - a) × (c - a)`` for ``(k, 2)`` float64 points:
    positive when ``a, b, c`` turn counter-clockwise."""
    try:
        return _module("p3d_cli.geometry.predicates").orient2d(a, b, c, safe)
    except Unavailable:
        pass
    left = (a[:, 0] - c[:, 0]) * (b[:, 1] - c[:, 1])
    right = (a[:, 1] - c[:, 1]) * (b[:, 0] - c[:, 0])
    det = left - right
    out = (det > 0).astype(np.int8) - (det < 0).astype(np.int8)
    unsure = ~(np.abs(det) > _CCW_BOUND * (np.abs(left) + np.abs(right))) | (not safe)
    for row in np.flatnonzero(unsure).tolist():
        (ax, ay), (bx, by), (cx, cy) = ([Fraction(float(x)) for x in p[row]] for p in (a, b, c))
        value = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)
        out[row] = (value > 0) - (value < 0)
    return out


# ---------------------------------------------------------------------------------------------
# Welding, nesting and self-intersections: the exact tests of p3d check.
# ---------------------------------------------------------------------------------------------

def weld_points(points: np.ndarray, tolerance: float):
    """``(target, weld)``: for every point ``(m, 3)`` the smallest index of the points it is
    merged with (transitively, closer than ``tolerance``), and what was merged
    (``p3d_cli.mesh.weld.Weld``: count and largest distance).

    Raises
    ------
    Unavailable
    """
    return _module("p3d_cli.mesh.weld").weld_points(points, tolerance)


def check_tolerance(tolerance: float) -> float:
    """``tolerance`` as a positive finite float (``UsageError`` naming ``weld`` otherwise)."""
    from p3d_cli.errors import UsageError

    value = float(tolerance)
    if not (np.isfinite(value) and value > 0):
        raise UsageError("weld", f"tolerance {tolerance!r} is not a positive number",
                         "give the largest distance between vertices to merge, in the file's units")
    return value


def nesting_depths(points: np.ndarray, faces: np.ndarray, labels: np.ndarray, count: int,
                   closed: np.ndarray) -> dict[int, int]:
    """How many closed shells lie around each closed shell, decided exactly.

    Parameters
    ----------
    points : (m, 3) float64
    faces : (k, 3) int
    labels : (k,) int
        Shell of every face, ``0..count-1`` numbered by first face.
    closed : (s,) int
        The closed shells (the others take no part).

    Returns
    -------
    dict
        ``{shell: depth}`` for every closed shell (0: in no other).

    Raises
    ------
    Unavailable
    """
    closed = np.asarray(closed, dtype=np.int64)
    if closed.size <= 1:
        return {int(s): 0 for s in closed}
    nesting = _module("p3d_cli.mesh.nesting")
    layout_module = _module("p3d_cli.mesh.layout")
    from p3d_cli.mesh.shells import Components

    open_shells = np.setdiff1d(np.arange(count), closed)
    layout = layout_module.Layout(np.asarray(faces).ravel(), len(points), Components(labels, count),
                                  np.zeros(0, dtype=np.int64), np.zeros((0, 2), dtype=np.int64), open_shells)
    found = nesting.shell_nesting(np.asarray(points, dtype=np.float64), faces, layout,
                                  np.zeros((0, 2), dtype=np.int64))
    depth: dict[int, int] = {}
    for shell in closed.tolist():
        d, outer = 0, found.parent.get(shell)
        while outer is not None:
            d += 1
            outer = found.parent.get(outer)
        depth[shell] = d
    return depth


def self_intersections(points: np.ndarray, faces: np.ndarray):
    """Every pair of faces whose interiors cross or overlap
    (``p3d_cli.mesh.solidity_report.SelfIntersections``).

    Raises
    ------
    Unavailable
    """
    return _module("p3d_cli.mesh.intersections").self_intersections(np.asarray(points, dtype=np.float64), faces)


def new_face_crossings(points: np.ndarray, faces: np.ndarray, new: np.ndarray) -> np.ndarray:
    """The faces among ``new`` (indices into ``faces``) whose interiors cross or overlap
    another face: only faces whose boxes meet the new faces' box take part.

    Raises
    ------
    Unavailable
    """
    new = np.asarray(new, dtype=np.int64)
    if new.size == 0:
        return new
    _module("p3d_cli.mesh.intersections")
    corners = np.asarray(points, dtype=np.float64)[faces]
    lo, hi = corners[new].min(axis=(0, 1)), corners[new].max(axis=(0, 1))
    near = np.flatnonzero(((corners.min(axis=1) <= hi) & (corners.max(axis=1) >= lo)).all(axis=1))
    found = self_intersections(points, np.asarray(faces)[near])
    pairs = near[found.pairs] if len(found.pairs) else np.zeros((0, 2), dtype=np.int64)
    hit = np.unique(pairs.ravel())
    return np.intersect1d(hit, new)
