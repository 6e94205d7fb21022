"""Checking a robot description's declared inertials: possible, and consistent with the geometry.

Rules, per link (each problem names its rule):

- ``mass > 0``: the mass is positive and finite.
- ``symmetric``: the tensor equals its transpose (to 1e-9 of its largest entry).
- ``positive definite``: every principal moment is positive.
- ``triangle inequality``: ``I1 + I2 >= I3`` for the principal moments (to ``RTOL``: the numbers
  in a file carry few digits). No body breaks it (``p3d_cli.inertia.breaks_triangle_inequality``).
- ``com inside``: the centre of mass lies in the bounding box of the link's geometry, widened by
  ``com_slack`` of its diagonal on every side.
- ``principal moments``: for a link whose geometry is a closed solid, each declared principal
  moment is within a factor ``tolerance`` of the geometry's at the declared mass (uniform
  density). Real links are not uniform, so the default factor is loose (2).
- ``density``: the declared mass over the geometry's volume lies in ``density_range`` (kg/m³):
  a mass in grams in a metre model, or a mesh in millimetres without its scale, is off by 1000
  or 1e9 and lands far outside.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from p3d_cli.errors import RangeError
from p3d_cli.robots.geometry import LinkGeometry, measure_link
from p3d_cli.robots.model import Link, Robot

#: Relative slack of the triangle inequality for declared numbers (a file's few digits).
RTOL = 1e-6
#: Plausible densities of a link, kg/m³ (a hollow plastic cover to a solid tungsten weight).
DENSITY_RANGE = (50.0, 25_000.0)


@dataclass(frozen=True)
class Problem:
    """One failed rule: ``rule``, the offending ``value`` and the message."""

    rule: str
    value: object
    message: str


@dataclass
class LinkCheck:
    """The verdict on one link.

    Attributes
    ----------
    link : str
    problems : list of Problem
    notes : list of str
        What was not checked and why (no inertial declared, no geometry, geometry not a solid).
    implied_density : float or None
    moment_ratios : (3,) float64 or None
        Declared over geometric principal moments, ascending order of each.
    """

    link: str
    problems: list[Problem] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    implied_density: float | None = None
    moment_ratios: np.ndarray | None = None

    @property
    def ok(self) -> bool:
        return not self.problems


def check_robot(robot: Robot, *, tolerance: float = 2.0, role: str = "collision", com_slack: float = 0.05,
                density_range: tuple[float, float] = DENSITY_RANGE) -> list[LinkCheck]:
    """Check every link's declared inertial (see the module's rules).

    Parameters
    ----------
    robot : Robot
    tolerance : float
        Factor (> 1) allowed between declared and geometric principal moments.
    role : {"collision", "visual"}
        Which geometry the inertials are compared with.
    com_slack : float
        Widening of the geometry's bounds for the centre of mass, as a fraction of its diagonal.
    density_range : (float, float)
        Plausible implied densities, kg/m³.

    Raises
    ------
    UsageError
        A tolerance not above 1, a bad range.
    InputError
        A mesh that cannot be read.
    """
    from p3d_cli.errors import UsageError

    if not tolerance > 1:
        raise UsageError("tolerance", f"{tolerance!r} is not a factor above 1", "give e.g. 2")
    if not 0 < density_range[0] < density_range[1]:
        raise UsageError("density_range", f"{density_range!r} is not LOW < HIGH, both positive",
                         "give e.g. 50,25000 (kg/m^3)")
    return [check_link(link, robot.path, tolerance, role, com_slack, density_range) for link in robot.links]


def check_link(link: Link, source: str, tolerance: float, role: str, com_slack: float,
               density_range: tuple[float, float]) -> LinkCheck:
    """One link's verdict."""
    out = LinkCheck(link.name, notes=list(link.problems))
    inertial = link.inertial
    if inertial is None:
        out.notes.append("declares no inertial")
        return out
    mass, tensor = inertial.mass, inertial.inertia
    if not (np.isfinite(mass) and mass > 0):
        out.problems.append(Problem("mass > 0", mass, f"mass {mass:g} is not positive"))
    principal = _tensor_rules(out, tensor)
    positive = bool(np.isfinite(mass) and mass > 0)
    try:
        geometry = measure_link(link, role, source, mass=mass if positive else None)
    except RangeError as exc:
        out.problems.append(Problem("density", mass, f"{exc.what}: no link is that heavy"))
        return out
    if geometry is None:
        out.notes.append(f"has no {role} geometry: checked the inertial alone")
        return out
    _geometry_rules(out, inertial, principal if positive else None, geometry, tolerance, com_slack,
                    density_range)
    return out


def _tensor_rules(out: LinkCheck, tensor: np.ndarray) -> np.ndarray | None:
    """The tensor's own rules; its principal moments (None when not finite or not positive)."""
    if not np.all(np.isfinite(tensor)):
        out.problems.append(Problem("positive definite", tensor.tolist(), "the inertia is not finite"))
        return None
    # Work on the tensor divided by its largest entry, so that no sum overflows (a file may hold
    # 1e308); the eigenvalues scale back by the same factor.
    scale = max(float(np.abs(tensor).max()), 1e-300)
    unit = tensor / scale
    asymmetry = float(np.abs(unit - unit.T).max())
    if asymmetry > 1e-9:
        out.problems.append(Problem("symmetric", asymmetry * scale,
                                    f"the inertia is not symmetric (off by {asymmetry * scale:g})"))
    principal = np.linalg.eigvalsh(0.5 * (unit + unit.T))
    with np.errstate(over="ignore"):  # 1e308-sized moments may come back as inf: still reported
        principal = principal * scale
        sums = principal[0] + principal[1]
    if principal[0] <= 0:
        out.problems.append(Problem("positive definite", principal.tolist(),
                                    f"principal moments {_vec(principal)}: not all positive"))
        return None
    if sums < principal[2] * (1 - RTOL):
        out.problems.append(Problem("triangle inequality", principal.tolist(),
                                    f"principal moments {_vec(principal)}: I1 + I2 = "
                                    f"{sums:.6g} < I3 = {principal[2]:.6g}"))
    return principal


def _geometry_rules(out: LinkCheck, inertial, principal, geometry: LinkGeometry, tolerance: float,
                    com_slack: float, density_range) -> None:
    result = geometry.result
    if result is None:
        out.notes.append(f"geometry not compared: {geometry.problems[0]}")
        return
    bounds = result.facts.bounds
    if bounds is not None:
        slack = com_slack * bounds.diagonal + 1e-12
        c = inertial.center
        if np.any(c < bounds.min - slack) or np.any(c > bounds.max + slack):
            out.problems.append(Problem("com inside", c.tolist(), f"centre of mass {_vec(c)} is outside the "
                                        f"geometry's bounds {_vec(bounds.min)} .. {_vec(bounds.max)} "
                                        f"(widened by {com_slack:g} of the diagonal)"))
    if not geometry.solid:
        out.notes.append("geometry is not a closed solid, so its moments and density are not compared: "
                         + "; ".join(geometry.problems))
        return
    if principal is None:
        return
    volume = result.properties.volume
    with np.errstate(all="ignore"):  # extreme declared numbers: inf or nan ratios fail below
        density = inertial.mass / volume
        expected = result.properties.principal_moments
        ratios = principal / expected
    out.implied_density = density
    lo, hi = density_range
    if not lo <= density <= hi:  # nan fails too
        out.problems.append(Problem("density", density, f"mass {inertial.mass:g} kg over the geometry's volume "
                                    f"{volume:.6g} m^3 is {density:.6g} kg/m^3, outside {lo:g}..{hi:g} "
                                    "(a unit slip: grams for kg, or a mesh in mm without its scale?)"))
    out.moment_ratios = ratios
    if not np.all((ratios <= tolerance) & (ratios >= 1 / tolerance)):
        out.problems.append(Problem("principal moments", ratios.tolist(),
                                    f"principal moments {_vec(principal)} are {_vec(ratios, 3)} times the "
                                    f"geometry's at this mass {_vec(expected)}, beyond a factor {tolerance:g}"))


def _vec(v, digits: int = 6) -> str:
    return "(" + ", ".join(f"{float(x):.{digits}g}" for x in v) + ")"
