"""Value types a constraint solve returns."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from p3d_cli.records import Record


@dataclass(frozen=True)
class BodyState:
    """One body after the solve (or after the last step).

    Attributes
    ----------
    name : str
    fixed : bool
    position : (3,) float64
        World position of the body frame's origin.
    rotation : (4,) float64
        Unit quaternion ``[w, x, y, z]``, body to world.
    center_of_mass : (3,) float64 or None
        World frame; None for a body whose mass properties were never needed.
    velocity : (3,) float64
        Of the centre of mass, world frame.
    angular_velocity : (3,) float64
        World frame.
    constrained : bool
        Some constraint links it.
    """

    name: str
    fixed: bool
    position: np.ndarray
    rotation: np.ndarray
    center_of_mass: np.ndarray | None
    velocity: np.ndarray
    angular_velocity: np.ndarray
    constrained: bool


@dataclass(frozen=True)
class ConstraintOutcome:
    """One constraint after the solve.

    Attributes
    ----------
    type, a, b : str
    impulse : (3,) float64 or float
        Impulse on body ``b``, world frame (``a`` receives the opposite). A bar's is the signed
        scalar along the unit vector from ``a``'s attachment point to ``b``'s (positive pushes
        apart).
    angular_impulse : (3,) float64 or None
        Hinge only: the angular impulse on ``b``, perpendicular to the axis.
    error : float
        Euclidean norm of the constraint's velocity equations after the solve (m/s, and rad/s
        for a hinge's two angular rows).
    position_error : float
        Euclidean norm of its position equations (gap in length units; a hinge adds the
        sine of its axis misalignment; a bar gives |distance - length|).
    island : int
        Index of its island.
    """

    type: str
    a: str
    b: str
    impulse: object
    angular_impulse: np.ndarray | None
    error: float
    position_error: float
    island: int


@dataclass(frozen=True)
class SolveResult(Record):
    """What ``p3d solve`` reports.

    Attributes
    ----------
    bodies : tuple of BodyState
        Scene order.
    constraints : tuple of ConstraintOutcome
        Scene order.
    rank : int
        Rank of the system ``J M⁻¹ Jᵀ`` (of the last velocity solve when stepping).
    equations : int
        Its number of rows.
    islands : int
        Independent groups solved separately.
    kinetic_energy : (float, float)
        Before and after; fixed bodies excluded.
    momentum : ((3,), (3,)) float64
        Total linear momentum of the free bodies, before and after.
    angular_momentum : ((3,), (3,)) float64
        Total angular momentum of the free bodies about the world origin, before and after.
    steps : int
    time : float
        Simulated time (``steps * dt``).
    max_position_error : float
        Largest constraint position error after correction over all steps (or of the initial
        state for a single solve).
    """

    bodies: tuple[BodyState, ...]
    constraints: tuple[ConstraintOutcome, ...]
    rank: int
    equations: int
    islands: int
    kinetic_energy: tuple[float, float]
    momentum: tuple[np.ndarray, np.ndarray]
    angular_momentum: tuple[np.ndarray, np.ndarray]
    steps: int = 0
    time: float = 0.0
    max_position_error: float = 0.0

    @property
    def redundant(self) -> int:
        """Number of redundant equations (``equations - rank``)."""
        return self.equations - self.rank

    def body(self, name: str) -> BodyState:
        """The body named ``name`` (KeyError when the scene has none)."""
        for body in self.bodies:
            if body.name == name:
                return body
        raise KeyError(name)

    _has_settings = False  # p3d solve reads no project settings

    def _record(self) -> dict[str, Any]:
        return solve_record(self)


def solve_record(result: SolveResult) -> dict:
    """The JSON object of ``p3d solve`` (stable keys; see docs/solve.md)."""
    bodies = {}
    for body in result.bodies:
        bodies[body.name] = {
            "fixed": body.fixed,
            "position": body.position,
            "rotation": body.rotation,
            "center_of_mass": body.center_of_mass,
            "velocity": body.velocity,
            "angular_velocity": body.angular_velocity,
            "constrained": body.constrained,
        }
    constraints = []
    for c in result.constraints:
        entry = {"type": c.type, "a": c.a, "b": c.b, "impulse": c.impulse, "error": c.error,
                 "position_error": c.position_error, "island": c.island}
        if c.angular_impulse is not None:
            entry["angular_impulse"] = c.angular_impulse
        constraints.append(entry)
    return {
        "bodies": bodies,
        "constraints": constraints,
        "rank": result.rank,
        "equations": result.equations,
        "redundant": result.redundant,
        "islands": result.islands,
        "kinetic_energy": {"before": result.kinetic_energy[0], "after": result.kinetic_energy[1]},
        "momentum": {"before": result.momentum[0], "after": result.momentum[1]},
        "angular_momentum": {"before": result.angular_momentum[0], "after": result.angular_momentum[1]},
        "steps": result.steps,
        "time": result.time,
        "max_position_error": result.max_position_error,
        "frame": "world; velocity is the centre of mass's; angular momentum about the world origin; "
                 "impulses act on body b (a receives the opposite)",
    }
