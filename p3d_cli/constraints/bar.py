"""Bar: two body points keep their distance (the Physics3D note's eqs. 39-45; docs/method.md, "Bar").

With ``d`` the unit vector from ``a``'s attachment point to ``b``'s, the velocity equation (1 row)
is ``(v_b + ω_b × r_b - v_a - ω_a × r_a)·d = 0``, i.e. ``ME = [dᵀ, (r × d)ᵀ]`` (eq. 44-45, right as
written). The multiplier ``λ`` is the impulse on ``b`` along ``d``: positive pushes the bodies
apart (the bar in compression), negative pulls them together; ``a`` receives ``-λ d``.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints import scalar, values
from p3d_cli.constraints.rotation import cross, cross_rows, quat_to_matrix
from p3d_cli.errors import SceneError

#: The keys of its scene entry besides ``type``, ``a`` and ``b`` (docs/solve.md).
KEYS = ("attach_a", "attach_b", "length")
#: Rows per constraint.
EQUATIONS = 1
#: Body-frame vectors its world geometry turns (``hinge.TURNED``): none.
TURNED: tuple = ()


def read(spec: dict, place: str, body_a, body_b, attach_a, attach_b) -> dict:
    """Its own values of a scene entry (``ConstraintSpec.values``): the length, by default the
    distance between the attachment points where the scene places the bodies."""
    world_a = body_a.position + quat_to_matrix(body_a.rotation) @ attach_a
    world_b = body_b.position + quat_to_matrix(body_b.rotation) @ attach_b
    with np.errstate(all="ignore"):     # an overflow is checked for just below
        gap = float(np.linalg.norm(world_b - world_a))
    if not np.isfinite(gap):
        raise SceneError(place, "the distance between the bar's attachment points overflows float64",
                         "give positions and attachments in units that keep them nearer 1")
    if spec.get("length") is not None:
        length = values.number(spec["length"], f"{place}.length")
        if length <= 0:
            raise SceneError(f"{place}.length", f"a bar of length {spec['length']!r} has no direction",
                             "give a positive length, or use a ball joint to join two points")
    else:
        length = gap
    if gap == 0.0:
        raise SceneError(place, "the bar's two attachment points coincide, so it has no direction",
                         "place the bodies so the points are apart, or use a ball joint")
    return {"length": length}


def direction(geo) -> np.ndarray:
    """Unit vector from ``p_a`` to ``p_b``.

    Raises
    ------
    SceneError
        The points coincide: a bar of zero length has no direction.
    """
    d = geo.p_b - geo.p_a
    norm = float(np.linalg.norm(d))
    if norm == 0.0:
        raise met_error(geo.where)
    return d / norm


def met_error(where: str) -> SceneError:
    """The error of a bar whose attachment points have met (it has no direction)."""
    return SceneError(where or "bar", "the attachment points have come together, so the bar has "
                      "no direction", "use a ball joint to join two points, or a smaller --dt")


def jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (1, 6)."""
    d = direction(geo)
    jb = np.concatenate([d, cross(geo.r_b, d)])[None, :]
    ja = -np.concatenate([d, cross(geo.r_a, d)])[None, :]
    return ja, jb


def position_error(spec, geo) -> np.ndarray:
    """(1,): the distance between the points minus the bar's length."""
    return np.array([np.linalg.norm(geo.p_b - geo.p_a) - spec.values["length"]])


def impulse(geo, lam: np.ndarray) -> dict:
    """The impulse on ``b`` along the bar (scalar) and as a world vector."""
    return {"impulse": float(lam[0]), "impulse_vector": lam[0] * direction(geo)}


class Rows:
    """The array form (``rows.RowSet``): the rows of every bar of a scene at once."""

    def __init__(self, specs, ks: np.ndarray, offsets: np.ndarray) -> None:
        self.ks = ks
        self.rows = offsets[ks]
        self.length = np.array([specs[k].values["length"] for k in ks], dtype=np.float64)
        self.where = [specs[k].where for k in ks]

    def template(self, ja: np.ndarray, jb: np.ndarray) -> None:
        """No constant entries."""

    def errors(self, geo, g: int, out: np.ndarray) -> None:
        gap = geo.gap[self.ks]
        out[self.rows] = np.sqrt((gap * gap).sum(axis=1)) - self.length

    def jacobian(self, geo, g: int, ja: np.ndarray, jb: np.ndarray) -> None:
        d = directions(geo.gap[self.ks], self.where)
        rows = self.rows
        ja[rows, :3], jb[rows, :3] = -d, d
        ja[rows, 3:] = -cross_rows(geo.r_a[self.ks], d)
        jb[rows, 3:] = cross_rows(geo.r_b[self.ks], d)


def directions(gap: np.ndarray, where) -> np.ndarray:
    """Unit vectors along (b, 3) bar gaps; a bar whose points met is one ``SceneError``."""
    norm = np.sqrt((gap * gap).sum(axis=1))
    if not norm.all():
        raise met_error(where[int(np.flatnonzero(norm == 0.0)[0])])
    return gap / norm[:, None]


class SmallJoint(scalar.Joint):
    """The scalar form (``small_step``): the distance minus the length; ``[-d, -(r_a × d)]`` and
    ``[d, r_b × d]``."""

    __slots__ = ("length",)
    rows = EQUATIONS
    constants = ()
    single_row = True
    length: float

    def configure(self, spec, rot) -> None:
        self.length = float(spec.values["length"])

    def evaluate(self, com, rot) -> list[float]:
        gap = self.points(com, rot)
        ra, rb = self._state
        norm = math.sqrt(gap[0] * gap[0] + gap[1] * gap[1] + gap[2] * gap[2])
        self._state = (ra, rb, gap, norm)
        return [norm - self.length]

    def columns(self) -> list[tuple[int, int]]:
        return [(0, j) for j in range(6)]

    def entries(self) -> list[float]:
        """``[-d, -(r_a × d)]`` and ``[d, r_b × d]``, ``d`` the unit vector from ``p_a`` to ``p_b``."""
        ra, rb, gap, norm = self._state
        if norm == 0.0:
            raise met_error(self.where)
        d = (gap[0] / norm, gap[1] / norm, gap[2] / norm)
        out: list[float] = []
        if self.free_a:
            ca = scalar.cross(ra, d)
            out += [-d[0], -d[1], -d[2], -ca[0], -ca[1], -ca[2]]
        if self.free_b:
            out += [*d, *scalar.cross(rb, d)]
        return out
