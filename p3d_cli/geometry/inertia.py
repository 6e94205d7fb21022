"""Mass properties (mass, centre of mass, inertia tensors, principal frame) from ``Moments``.

The one copy of each rule about mass and inertia: the density/mass rule (``density_for``), the
inertia of second moments, the parallel-axis theorem, the principal frame and the triangle
inequality every solid's principal moments obey (``breaks_triangle_inequality``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import RangeError, UsageError
from p3d_cli.geometry.rotation import matrix_quaternion, matrix_rpy
from p3d_cli.results import MassProperties, Moments
from p3d_cli.warning_codes import CodedWarning


def inertia_from_second_moments(second: np.ndarray) -> np.ndarray:
    """Positive inertia tensor ``I = tr(S) E - S`` from second moments ``S = ∫ r rᵀ dm``.

    Parameters
    ----------
    second : (3, 3) float64

    Returns
    -------
    (3, 3) float64
        ``Ixx = ∫ (y² + z²) dm``, ``Ixy = -∫ x y dm`` (docs/method.md, "Inertia sign").

    Notes
    -----
    The diagonal is summed as ``Syy + Szz`` (and so on), not as ``tr(S) - Sxx``: for a needle
    (``Sxx`` 1e24 times the others) the subtraction cancels to 0, a singular inertia.
    """
    second = np.asarray(second, dtype=np.float64)
    out = -second
    out[0, 0] = second[1, 1] + second[2, 2]
    out[1, 1] = second[0, 0] + second[2, 2]
    out[2, 2] = second[0, 0] + second[1, 1]
    return out


def shifted_inertia(inertia_com: np.ndarray, mass: float, center: np.ndarray, point) -> np.ndarray:
    """Inertia about ``point`` from inertia about the centre of mass (parallel-axis theorem).

    ``I_p = I_c + m (|d|² E - d dᵀ)`` with ``d = c - p``.
    """
    d = np.asarray(center, dtype=np.float64) - np.asarray(point, dtype=np.float64)
    return inertia_com + mass * (np.dot(d, d) * np.eye(3) - np.outer(d, d))


def principal_rotation(axes: np.ndarray) -> dict[str, np.ndarray]:
    """The rotation of a principal frame (``principal_frame``'s axes as columns), as the
    ``MassProperties`` fields ``principal_quaternion`` (``[w, x, y, z]``, MJCF) and
    ``principal_rpy`` (URDF roll, pitch, yaw)."""
    return {"principal_quaternion": matrix_quaternion(axes.T), "principal_rpy": matrix_rpy(axes.T)}


def principal_frame(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments (ascending) and a right-handed frame of principal axes.

    Parameters
    ----------
    inertia : (3, 3) float64, symmetric

    Returns
    -------
    moments : (3,) float64
        Eigenvalues in ascending order.
    axes : (3, 3) float64
        Row ``i`` is the unit axis of ``moments[i]``. Where moments coincide (to 1e-10 of the
        largest), the axes inside that eigenspace are the world axes x, y, z projected onto it
        and orthonormalised in that order, so a sphere or cube gets the world frame and a
        cylinder about z gets x and y. Sign rule: rows 0 and 1 have their largest-magnitude
        component positive (the first such component on a tie); row 2 is ``row0 × row1``, so
        the rows form a proper rotation.
    """
    sym = 0.5 * (inertia + inertia.T)
    values, vectors = np.linalg.eigh(sym)
    axes = vectors.T.copy()
    tol = 1e-10 * max(float(np.abs(values).max()), np.finfo(float).tiny)
    start = 0
    while start < 3:
        stop = start + 1
        while stop < 3 and values[stop] - values[start] <= tol:
            stop += 1
        if stop - start > 1:
            axes[start:stop] = _world_basis_of(axes[start:stop])
        start = stop
    for i in (0, 1):
        k = int(np.argmax(np.abs(axes[i])))
        if axes[i, k] < 0:
            axes[i] = -axes[i]
    axes[2] = np.cross(axes[0], axes[1])
    axes[2] /= np.linalg.norm(axes[2])
    return values, axes + 0.0  # + 0.0 turns -0.0 into 0.0 for tidy output


def _world_basis_of(span: np.ndarray) -> np.ndarray:
    """An orthonormal basis of the row space of ``span`` built from the projected world axes."""
    projector = span.T @ span
    basis: list[np.ndarray] = []
    for e in np.eye(3):
        v = projector @ e
        for b in basis:
            v = v - np.dot(v, b) * b
        norm = np.linalg.norm(v)
        if norm > 1e-6:
            basis.append(v / norm)
        if len(basis) == len(span):
            break
    return np.array(basis)


def density_for(volume: float, density: float | None = None, mass: float | None = None) -> float:
    """The density of a uniform solid: ``density``, else ``mass / |volume|``, else 1.

    Raises
    ------
    UsageError
        Both ``density`` and ``mass`` given, or ``mass`` given for a solid with no volume.
    """
    if density is not None and mass is not None:
        raise UsageError("mass, density", "both given; they are exclusive",
                         "give one: the other follows from the volume")
    for name, value in (("mass", mass), ("density", density)):
        if value is not None and 0 < abs(value) < np.finfo(np.float64).tiny:
            raise UsageError(name, f"{value!r} is below float64's normal range (about 2.2e-308), "
                             "where it keeps only a few digits", "give it in a larger unit")
    if mass is not None:
        if volume == 0.0:
            raise UsageError("mass", "the input encloses no volume, so no density follows from a mass",
                             "give density= instead")
        return mass / abs(volume)
    return 1.0 if density is None else density


def breaks_triangle_inequality(principal, rtol: float = 1e-9) -> bool:
    """True when ascending principal moments break ``I1 + I2 >= I3`` (beyond ``rtol``), or the
    smallest is negative: no solid has such an inertia (a bad mesh or bad data does).

    Parameters
    ----------
    principal : (3,) array_like of float, ascending
    rtol : float
        Relative slack for rounding, of the largest moment.
    """
    p = np.asarray(principal, dtype=np.float64)
    scale = max(float(np.abs(p).max()), 1e-300)
    # Python floats: a sum of moments near float64's largest is inf (rightly: no break) without
    # numpy's overflow warning.
    i1, i2, i3 = (float(x) for x in p)
    return i1 < -rtol * scale or i1 + i2 < i3 * (1 - rtol)


def mass_properties(moments: Moments, *, density: float | None = None, mass: float | None = None,
                    about=None, where: str = "") -> MassProperties:
    """Mass properties of a uniform solid from its volume moments.

    Parameters
    ----------
    moments : Moments
    density : float, optional
        Mass per unit volume; default 1. Exclusive with ``mass``.
    mass : float, optional
        Total mass; the density becomes ``mass / |volume|`` (an inward-wound mesh keeps its
        negative sign in ``mass``, ``inertia`` and everything derived from them).
    about : (3,) array_like, optional
        A point for ``inertia_about``.
    where : str, optional
        The input's name, for the error when a result overflows.

    Raises
    ------
    UsageError
        Both ``density`` and ``mass`` given, or ``mass`` given for a solid with no volume.
    RangeError
        A result overflows float64 (a huge part, density, or distance from the origin).
    """
    density = density_for(moments.volume, density, mass)
    about_point = None if about is None else np.asarray(about, dtype=np.float64).reshape(3)
    with np.errstate(all="ignore"):  # overflow is detected below and reported as one error
        total = density * moments.volume
        _check_finite(where, "the mass", total)
        if moments.is_empty:
            return MassProperties(moments.volume, density, total, None, None, None, None, None, None,
                                  about_point, None)
        second = density * moments.central
        inertia = inertia_from_second_moments(second)
        _check_finite(where, "the inertia", moments.center, second, inertia)
        _check_normal(where, moments, total, second)
        inertia_origin = shifted_inertia(inertia, total, moments.center, np.zeros(3))
        _check_finite(where, "the inertia about the origin", inertia_origin)
        inertia_about = None
        if about_point is not None:
            inertia_about = shifted_inertia(inertia, total, moments.center, about_point)
            _check_finite(where, "the inertia about the point given", inertia_about)
    principal, axes = principal_frame(inertia)
    return MassProperties(moments.volume, density, total, moments.center.copy(), inertia,
                          inertia_origin, principal, axes, second, about_point, inertia_about,
                          **principal_rotation(axes))


def _check_normal(where: str, moments: Moments, mass: float, second: np.ndarray) -> None:
    """Refuse a mass or second moment that a tiny density pushed below float64's normal range
    (2**-1022), where it keeps only a few bits: a silently wrong number."""
    tiny = np.finfo(np.float64).tiny
    lost = moments.volume != 0 and abs(mass) < tiny
    lost = lost or bool(np.any((np.diag(moments.central) != 0) & (np.abs(np.diag(second)) < tiny)))
    if lost:
        raise RangeError(where or "result", "the mass or inertia underflows float64",
                         "measure in a smaller unit, or with a larger density")


def _check_finite(where: str, what: str, *values) -> None:
    if not all(np.isfinite(v).all() for v in values):
        raise RangeError(where or "result", f"{what} overflows float64",
                         "measure in a larger unit, or nearer the origin, or with a smaller density")


def implausibilities(props: MassProperties, bounds=None, method: str = "exact") -> list[CodedWarning]:
    """Plain-words warnings for a result no solid can have: only a bad mesh gives one.

    A solid has positive volume and mass, principal moments that are positive and satisfy the
    triangle inequality (``I1 + I2 >= I3``: ``I3 = ∫(x² + y²) dm <= I1 + I2 = ∫(x² + y² + 2z²) dm``
    in the principal frame), and its centre of mass inside its bounding box (the box is convex
    and holds every point). The triangle check is skipped for Monte Carlo estimates, whose
    noise can break the equality of a flat part.

    Parameters
    ----------
    props : MassProperties
    bounds : Bounds, optional
    method : str
    """
    out = []
    if props.volume <= 0 or props.mass <= 0:
        out.append(CodedWarning(f"volume {props.volume:.6g} and mass {props.mass:.6g} are not both positive, as a "
                                "solid's are: the mesh is inside out or not a solid", "implausible"))
    if (props.principal_moments is not None and method == "exact" and props.mass > 0
            and breaks_triangle_inequality(props.principal_moments)):
        out.append(CodedWarning("principal moments break the triangle inequality (or one is negative), which no "
                                "solid's do: the mesh probably intersects itself", "implausible"))
    if props.center_of_mass is not None and bounds is not None:
        slack = 1e-9 * max(bounds.diagonal, float(np.abs(bounds.max).max()), float(np.abs(bounds.min).max()))
        c = props.center_of_mass
        if np.any(c < bounds.min - slack) or np.any(c > bounds.max + slack):
            out.append(CodedWarning("the centre of mass lies outside the bounds, which no solid's does: the mesh is "
                                    "not a solid (inside-out or overlapping parts)", "implausible"))
    return out


def combine_mass_properties(parts, about=None) -> MassProperties:
    """The mass properties of several solids taken together (an assembly).

    Masses and volumes add; the centre is ``c = Σ mᵢ cᵢ / M``; second moments about it add with
    the parallel-axis terms, ``S = Σ (Sᵢ + mᵢ dᵢ dᵢᵀ)`` with ``dᵢ = cᵢ - c`` (Steiner's theorem
    on ``S = ∫ (x - c)(x - c)ᵀ dm``), and ``I = tr(S) E - S``. The density reported is the mean,
    ``M / V``.

    Parameters
    ----------
    parts : iterable of MassProperties
        Each in the same frame and units; parts without volume add nothing.
    about : (3,) array_like, optional

    Raises
    ------
    UsageError
        No part has mass.
    """
    parts = [p for p in parts if p.center_of_mass is not None]
    volume = float(sum(p.volume for p in parts))
    total = float(sum(p.mass for p in parts))
    if not parts or total == 0.0:
        raise UsageError("parts", "no part has mass", "give parts with a volume")
    center = sum(p.mass * p.center_of_mass for p in parts) / total
    second = np.zeros((3, 3))
    for p in parts:
        d = p.center_of_mass - center
        second = second + p.second_moments + p.mass * np.outer(d, d)
    inertia = inertia_from_second_moments(second)
    principal, axes = principal_frame(inertia)
    about_point = None if about is None else np.asarray(about, dtype=np.float64).reshape(3)
    inertia_about = None if about_point is None else shifted_inertia(inertia, total, center, about_point)
    return MassProperties(volume, total / volume if volume else 0.0, total, center, inertia,
                          shifted_inertia(inertia, total, center, np.zeros(3)), principal, axes, second,
                          about_point, inertia_about, **principal_rotation(axes))
