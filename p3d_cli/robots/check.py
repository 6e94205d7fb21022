"""Checking a robot description's declared inertials: possible, and consistent with the geometry.

Rules, per link (each problem names its rule):

- ``mass > 0``: the mass is positive and finite.
- ``symmetric``: the tensor equals its transpose (to 1e-9 of its largest entry).
- ``positive definite``: every principal moment is positive.
- ``triangle inequality``: ``I1 + I2 >= I3`` for the principal moments (to ``RTOL``: the numbers
  in a file carry few digits). No body breaks it (``p3d_cli.geometry.inertia.breaks_triangle_inequality``).
- ``com inside``: the centre of mass lies in the bounding box of the link's geometry, widened by
  ``com_slack`` of its diagonal on every side.
- ``moments``: for a link whose geometry is a closed solid, the declared tensor is compared
  with the geometry's at the declared mass (uniform density) in the link frame, axis by axis:
  about each principal axis ``u`` of the geometry, the declared moment ``uᵀ I u`` is within a
  factor ``tolerance`` of the geometry's. So a tensor with the right moments about the wrong
  axes fails (a rotor's axial moment declared about x, its geometry's axis z), which comparing
  sorted principal moments missed. Real links are not uniform, so the default factor is loose
  (2).
- ``density``: the declared mass over the geometry's volume lies in ``density_range`` (kg/m³):
  a mass in grams in a metre model, or a mesh in millimetres without its scale, is off by 1000
  or 1e9 and lands far outside.
- ``inertial required`` (``require_inertial``): a link with geometry declares an inertial.

Which geometry: ``role`` ``collision`` or ``visual``, or ``auto``: both where the link has
both, the one whose moments are closer to the declared ones (collision geometry is often a
crude primitive while the visual mesh is the part). Every verdict says the geometry used,
the density assumed (the declared mass over its volume) and the tolerance.

Massless frames: a link whose declared mass is at most ``MASSLESS`` kg (1 g), or that has
no geometry and a zero mass, is a frame (a camera or tool frame, a fingertip marker): it is
reported as such and not failed for a zero tensor; a negative or non-finite number still fails.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from p3d_cli.errors import RangeError
from p3d_cli.robots.geometry import LinkGeometry, measure_link
from p3d_cli.robots.model import Link, Robot

#: Relative slack of the triangle inequality for declared numbers (a file's few digits).
RTOL = 1e-6
#: Plausible densities of a link, kg/m³ (a hollow plastic cover to a solid tungsten weight).
DENSITY_RANGE = (50.0, 25_000.0)
#: Links declaring at most this mass (kg) are frames: massless or near-massless markers.
MASSLESS = 1e-3
#: Which geometry ``check_robot`` may compare with.
ROLES = ("collision", "visual", "auto")


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
        The density assumed: the declared mass over the geometry's volume (kg/m³).
    moment_ratios : (3,) float64 or None
        Declared over geometric moments about each principal axis of the geometry (ascending
        geometric moments).
    geometry : str or None
        The geometry compared with (``collision`` or ``visual``, with its stand-in for an open
        mesh), None when none was.
    stand_in : str or None
        What stood in for an open mesh (``open_mesh``): ``thin shell``, ``convex hull of ...``.
    tolerance : float
        The factor allowed between declared and geometric moments.
    frame : bool
        A massless or near-massless frame (mass at most ``MASSLESS``).
    role : str or None
        ``collision`` or ``visual``: the geometry compared with (None when none was).
    measured : LinkGeometry or None
        That geometry as measured, at the declared mass (for the report's pictures).
    """

    link: str
    problems: list[Problem] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    implied_density: float | None = None
    moment_ratios: np.ndarray | None = None
    geometry: str | None = None
    tolerance: float = 2.0
    frame: bool = False
    stand_in: str | None = None
    role: str | None = None
    measured: LinkGeometry | None = field(default=None, repr=False, compare=False)

    @property
    def ok(self) -> bool:
        return not self.problems

    @property
    def status(self) -> str:
        """``failed``, ``frame`` (a massless frame, passed) or ``ok``."""
        return "failed" if self.problems else "frame" if self.frame else "ok"

    @property
    def basis(self) -> str:
        """What the verdict rests on, in words: the geometry, density and tolerance."""
        if self.geometry is None:
            return "the inertial alone"
        density = "" if self.implied_density is None else f", density {self.implied_density:.6g} kg/m^3 from the " \
                                                          "declared mass"
        return f"{self.geometry} geometry{density}, tolerance x{self.tolerance:g}"


def check_robot(robot: Robot, *, tolerance: float = 2.0, role: str = "auto", com_slack: float = 0.05,
                density_range: tuple[float, float] = DENSITY_RANGE,
                require_inertial: bool = False, open_mesh: str = "refuse") -> list[LinkCheck]:
    """Check every link's declared inertial (see the module's rules).

    Parameters
    ----------
    robot : Robot
    tolerance : float
        Factor (> 1) allowed between declared and geometric principal moments.
    role : {"auto", "collision", "visual"}
        Which geometry the inertials are compared with (auto: the closer of the two).
    com_slack : float
        Widening of the geometry's bounds for the centre of mass, as a fraction of its diagonal.
    density_range : (float, float)
        Plausible implied densities, kg/m³.
    require_inertial : bool
        Fail links that have geometry but declare no inertial.
    open_mesh : {"refuse", "hull", "shell"}
        What stands in for geometry that bounds no solid: nothing (its moments and density
        are not compared; default), each open mesh's convex hull, or a thin shell of the
        declared mass over the link's surface (no density compared).

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
    from p3d_cli.robots.open_mesh import OPEN_MESH

    if open_mesh not in OPEN_MESH:
        raise UsageError("open_mesh", f"{open_mesh!r} is none of {', '.join(OPEN_MESH)}", "give shell, hull or refuse")
    if role not in ROLES:
        raise UsageError("role", f"{role!r} is none of {', '.join(ROLES)}", "give collision, visual or auto")
    out = []
    seen: dict[int, LinkCheck] = {}
    for link in robot.links:
        # The copies of a replicated MJCF body share their element and geometry: measured once.
        done = seen.get(id(link.node))
        if done is None:
            done = seen[id(link.node)] = check_link(link, robot.path, tolerance, role, com_slack, density_range,
                                                    require_inertial, open_mesh)
        out.append(done if done.link == link.name else dataclasses.replace(done, link=link.name))
    return out


def check_link(link: Link, source: str, tolerance: float, role: str, com_slack: float,
               density_range: tuple[float, float], require_inertial: bool = False,
               open_mesh: str = "refuse") -> LinkCheck:
    """One link's verdict."""
    out = LinkCheck(link.name, notes=list(link.problems), tolerance=tolerance)
    inertial = link.inertial
    roles = ("collision", "visual") if role == "auto" else (role,)
    has_geometry = any(link.geoms(r) for r in roles)
    if inertial is None:
        if require_inertial and has_geometry:
            out.problems.append(Problem("inertial required", None, "has geometry but declares no inertial "
                                        "(a simulator gives it a default or its geoms' mass)"))
        else:
            out.notes.append("declares no inertial")
        return out
    mass, tensor = inertial.mass, inertial.inertia
    if np.isfinite(mass) and 0 <= mass <= MASSLESS and (mass > 0 or not has_geometry):
        return _frame(out, mass, tensor)
    if not (np.isfinite(mass) and mass > 0):
        out.problems.append(Problem("mass > 0", mass, f"mass {mass:g} is not positive"))
    principal = _tensor_rules(out, tensor)
    positive = bool(np.isfinite(mass) and mass > 0)
    best: tuple[float, LinkCheck] | None = None
    for r in roles:
        try:
            geometry = measure_link(link, r, source, mass=mass if positive else None, open_mesh=open_mesh)
        except RangeError as exc:
            out.problems.append(Problem("density", mass, f"{exc.what}: no link is that heavy"))
            return out
        if geometry is None:
            continue
        trial = LinkCheck(link.name, tolerance=tolerance, geometry=r if geometry.stand_in is None else
                          f"{r} ({geometry.stand_in})", stand_in=geometry.stand_in, role=r, measured=geometry)
        _geometry_rules(trial, inertial, principal if positive else None, geometry, tolerance, com_slack,
                        density_range)
        distance = _distance(trial)
        if best is None or distance < best[0]:
            best = (distance, trial)
    if best is None:
        out.notes.append(f"has no {' or '.join(roles)} geometry: checked the inertial alone")
        return out
    trial = best[1]
    out.problems += trial.problems
    out.notes += trial.notes
    out.geometry, out.implied_density, out.moment_ratios = trial.geometry, trial.implied_density, trial.moment_ratios
    out.stand_in, out.role, out.measured = trial.stand_in, trial.role, trial.measured
    if role == "auto" and all(link.geoms(r) for r in roles):
        out.notes.append(f"compared with its {trial.geometry} geometry, the closer match")
    return out


def _distance(trial: LinkCheck) -> float:
    """How far a comparison is from agreeing: failed geometry rules, then the worst moment
    ratio's distance from 1 (a comparison that could not be made ranks last)."""
    rules = sum(1 for p in trial.problems if p.rule in ("com inside", "density", "moments"))
    if trial.moment_ratios is None or not np.all(np.isfinite(trial.moment_ratios)) \
            or not np.all(trial.moment_ratios > 0):
        return rules + 1e6
    return rules + float(np.max(np.abs(np.log(trial.moment_ratios))))


def _frame(out: LinkCheck, mass: float, tensor: np.ndarray) -> LinkCheck:
    """A massless or near-massless frame: passed, unless a number is negative or not finite."""
    out.frame = True
    out.notes.append(f"a massless frame (mass {mass:g} kg, at most {MASSLESS:g}): its inertia is not compared")
    if not np.all(np.isfinite(tensor)):
        out.problems.append(Problem("positive definite", tensor.tolist(), "the inertia is not finite"))
        return out
    scale = max(float(np.abs(tensor).max()), 1e-300)
    unit = tensor / scale  # scaled before the sum: 1e308 + 1e308 would overflow
    with np.errstate(over="ignore"):
        principal = np.linalg.eigvalsh(0.5 * (unit + unit.T)) * scale
    if principal[0] < -1e-9 * scale:
        out.problems.append(Problem("positive definite", principal.tolist(),
                                    f"principal moments {_vec(principal)}: one is negative"))
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
                         + "; ".join(geometry.problems) + " (open_mesh=hull or open_mesh=shell compares with a "
                         "stand-in)")
        return
    if geometry.stand_in:
        out.notes.append(f"the geometry is not a closed solid ({'; '.join(geometry.problems)}): compared with its "
                         f"{geometry.stand_in}")
    if principal is None:
        return
    volume = result.properties.volume
    shell = out.stand_in == "thin shell"  # a surface: no volume, so no density to compare
    with np.errstate(all="ignore"):  # extreme declared numbers: inf or nan ratios fail below
        density = None if shell else inertial.mass / volume
        expected, axes = _principal(result.properties.inertia)
        declared = np.einsum("ki,ij,kj->k", axes, inertial.inertia, axes)  # uᵀ I u for each axis u
        ratios = declared / expected
    out.implied_density = density
    lo, hi = density_range
    if density is not None and not lo <= density <= hi:  # nan fails too
        out.problems.append(Problem("density", density, f"mass {inertial.mass:g} kg over the geometry's volume "
                                    f"{volume:.6g} m^3 is {density:.6g} kg/m^3, outside {lo:g}..{hi:g} "
                                    "(a unit slip: grams for kg, or a mesh in mm without its scale?)"))
    out.moment_ratios = ratios
    if not np.all((ratios <= tolerance) & (ratios >= 1 / tolerance)):
        out.problems.append(Problem("moments", ratios.tolist(),
                                    f"about the geometry's principal axes {_axes(axes)}, the declared moments "
                                    f"{_vec(declared)} are {_vec(ratios, 3)} times the geometry's at this mass "
                                    f"{_vec(expected)}, beyond a factor {tolerance:g}"))


def _principal(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending) and axes (rows) of a tensor, computed on its scaled copy."""
    scale = max(float(np.abs(inertia).max()), 1e-300)
    moments, vectors = np.linalg.eigh(0.5 * (inertia + inertia.T) / scale)
    return moments * scale, vectors.T


def _axes(axes: np.ndarray) -> str:
    """Axes as link-frame names where they are (nearly) one: x, y, z; else their components."""
    names = []
    for u in axes:
        k = int(np.argmax(np.abs(u)))
        names.append("xyz"[k] if abs(u[k]) > 0.999 else _vec(u, 3))
    return "(" + ", ".join(names) + ")"


def _vec(v, digits: int = 6) -> str:
    return "(" + ", ".join(f"{float(x):.{digits}g}" for x in v) + ")"
