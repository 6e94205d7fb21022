"""Value types p3d returns: frozen dataclasses holding numpy arrays.

Conventions, stated once for every output:

- ``Moments`` are volume integrals (density-free): signed volume ``V = ∫ dV``, centre
  ``c = ∫ x dV / V`` and central second moments ``C = ∫ (x - c)(x - c)ᵀ dV``. They are
  the convention-free quantities that the Physics3D note's eq. 8-9 scale (docs/method.md, "Moments").
- Inertia is the standard positive tensor ``I = ∫ (|r|² E - r rᵀ) dm``: ``Ixx = ∫ (y² + z²) dm``,
  ``Ixy = -∫ x y dm`` (docs/method.md, "Inertia sign": the Physics3D note's eq. 3 has the
  opposite sign).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from p3d_cli.records import Record
from p3d_cli.warning_codes import CodedWarning, coded

@dataclass(frozen=True)
class Bounds:
    """An axis-aligned box.

    Attributes
    ----------
    min, max : (3,) float64
    """

    min: np.ndarray
    max: np.ndarray

    @property
    def size(self) -> np.ndarray:
        return self.max - self.min

    @property
    def center(self) -> np.ndarray:
        # Halves first: min + max overflows for a box near float64's largest (at 1e308).
        return 0.5 * self.min + 0.5 * self.max

    @property
    def diagonal(self) -> float:
        with np.errstate(over="ignore", under="ignore"):
            d = float(np.linalg.norm(self.max - self.min))
        if math.isfinite(d) and d > 2.0 ** -400:
            return d
        # The squares of a size past 1.34e154 overflow (and of a tiny one underflow), the
        # diagonal need not: hypot scales.
        return math.hypot(*(float(x) for x in self.max - self.min))

    def union(self, other: "Bounds") -> "Bounds":
        return Bounds(np.minimum(self.min, other.min), np.maximum(self.max, other.max))


@dataclass(frozen=True)
class MomentErrors:
    """A-priori bounds on the absolute rounding error of each ``Moments`` quantity.

    Attributes
    ----------
    volume : float
    center : (3,) float64
    central : (3, 3) float64
    """

    volume: float
    center: np.ndarray
    central: np.ndarray


@dataclass(frozen=True)
class Moments:
    """Volume integrals of a solid, about its own centre.

    Attributes
    ----------
    volume : float
        Signed volume; negative for an inward-wound closed mesh.
    center : (3,) float64 or None
        Centre of volume; None when the volume is zero (flat or empty shape).
    central : (3, 3) float64 or None
        ``∫ (x - c)(x - c)ᵀ dV``; None when the volume is zero.
    errors : MomentErrors or None
        Rounding-error bounds, where the method that produced the moments gives them.
    """

    volume: float
    center: np.ndarray | None
    central: np.ndarray | None
    errors: MomentErrors | None = None

    @property
    def is_empty(self) -> bool:
        return self.center is None


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of a solid of uniform density.

    Attributes
    ----------
    volume : float
        Signed volume.
    density : float
    mass : float
        ``density * volume``; negative when the volume is.
    center_of_mass : (3,) float64 or None
    inertia : (3, 3) float64 or None
        About the centre of mass, standard positive convention.
    inertia_origin : (3, 3) float64 or None
        About the world origin.
    about : (3,) float64 or None
        The point of ``inertia_about``, when the user asked for one.
    inertia_about : (3, 3) float64 or None
    principal_moments : (3,) float64 or None
        Eigenvalues of ``inertia``, ascending.
    principal_axes : (3, 3) float64 or None
        Row ``i`` is the unit axis of ``principal_moments[i]``; the rows form a right-handed
        frame (``axes[2] = axes[0] × axes[1]``), and ``axes[0]``, ``axes[1]`` each have their
        largest-magnitude component positive.
    second_moments : (3, 3) float64 or None
        ``∫ (x - c)(x - c)ᵀ dm`` about the centre of mass (``inertia = tr(S) E - S``).
    principal_quaternion : (4,) float64 or None
        The principal frame as a unit quaternion ``[w, x, y, z]`` (``w >= 0``): the rotation
        taking the world axes to the principal axes (its matrix has the axes as columns, so it
        is MJCF's ``<inertial quat=...>``, and ``I = R diag(principal_moments) Rᵀ``). Set with
        ``principal_axes`` by what computes them (``p3d_cli.geometry.inertia.principal_rotation``).
    principal_rpy : (3,) float64 or None
        The same rotation as URDF roll, pitch, yaw (radians).
    """

    volume: float
    density: float
    mass: float
    center_of_mass: np.ndarray | None
    inertia: np.ndarray | None
    inertia_origin: np.ndarray | None
    principal_moments: np.ndarray | None
    principal_axes: np.ndarray | None
    second_moments: np.ndarray | None
    about: np.ndarray | None = None
    inertia_about: np.ndarray | None = None
    principal_quaternion: np.ndarray | None = None
    principal_rpy: np.ndarray | None = None


@dataclass(frozen=True)
class MeshFacts:
    """What p3d learned about an input besides its integrals.

    Attributes
    ----------
    source : str
        The path or spec as the user gave it (``-`` for standard input).
    format : str
        ``stl-binary``, ``stl-ascii``, ``obj``, ``ply``, ``off``, ``meshio:<name>``, ``primitive``.
    faces : int
        Triangle count (tetrahedra for a volume mesh, 0 for a primitive).
    closed : bool or None
        Every edge shared by exactly two faces in opposite directions, vertices matched by
        exact coordinates; None where it does not apply (primitives, volume meshes).
    bounds : Bounds or None
    coordinate_dtype : str
        ``float32`` or ``float64``: the precision of the coordinates as stored.
    bounding : bool or None
        Every directed edge matched by as many uses the opposite way (true for closed meshes,
        and for non-manifold ones such as two cubes sharing an edge, which still bound a
        solid); None where it does not apply.
    wound_inward : bool
        The faces' signed volume was negative: the reported volume, mass and inertia are the
        enclosed solid's (positive), and ``-volume`` is the signed volume.
    """

    source: str
    format: str
    faces: int
    closed: bool | None
    bounds: Bounds | None
    coordinate_dtype: str = "float64"
    bounding: bool | None = None
    wound_inward: bool = False


@dataclass(frozen=True)
class PropsResult(Record):
    """One input's answer to ``p3d props``.

    Attributes
    ----------
    facts : MeshFacts
    properties : MassProperties
    method : str
        ``exact`` (divergence theorem / closed form) or ``montecarlo``.
    warnings : tuple of CodedWarning
        Plain-words warnings, each carrying its stable code (``warning_codes`` lists them).
    uncertainty : dict or None
        Same keys as the estimates (``volume``, ``center_of_mass``, ``inertia``): standard
        errors for Monte Carlo, rounding-error bounds for the exact method.
    details : dict
        How the result was made, for the record: ``samples`` and ``seed`` (Monte Carlo),
        ``placement`` (the scale, rotation and translation applied), ``tessellate``; for a part
        of an assembly, its ``name``.
    units : dict or None
        The unit of every quantity (``length``, ``volume``, ``density``, ``mass``, ``inertia``):
        SI or the output units asked for, or the mesh's own (``system: mesh``) without units.
    parts : tuple of PropsResult
        For an assembly, each part's result, placed in the assembly's frame (in the same units).
    """

    facts: MeshFacts
    properties: MassProperties
    method: str = "exact"
    warnings: tuple[CodedWarning, ...] = field(default_factory=tuple)
    uncertainty: dict | None = None
    details: dict = field(default_factory=dict)
    units: dict | None = None
    parts: tuple["PropsResult", ...] = field(default_factory=tuple)

    def __post_init__(self):
        object.__setattr__(self, "warnings", coded(self.warnings, self.facts.source))

    # One step to the common quantities (``properties`` and ``facts`` hold them all).
    @property
    def volume(self) -> float:
        """``properties.volume``."""
        return self.properties.volume

    @property
    def mass(self) -> float:
        """``properties.mass``."""
        return self.properties.mass

    @property
    def density(self) -> float:
        """``properties.density``."""
        return self.properties.density

    @property
    def center_of_mass(self) -> np.ndarray | None:
        """``properties.center_of_mass``."""
        return self.properties.center_of_mass

    @property
    def inertia(self) -> np.ndarray | None:
        """``properties.inertia``."""
        return self.properties.inertia

    @property
    def principal_moments(self) -> np.ndarray | None:
        """``properties.principal_moments``."""
        return self.properties.principal_moments

    @property
    def principal_axes(self) -> np.ndarray | None:
        """``properties.principal_axes``."""
        return self.properties.principal_axes

    @property
    def bounds(self) -> Bounds | None:
        """``facts.bounds``."""
        return self.facts.bounds

    def _record(self) -> dict[str, Any]:
        return props_record(self)

    @property
    def warning_codes(self) -> tuple[str, ...]:
        """The stable code of each warning, in the same order (``p3d_cli.warning_codes``)."""
        return tuple(w.code for w in self.warnings)

    def _repr_html_(self) -> str:
        """In a notebook: the numbers, and the part with its principal frame and inertia box."""
        from p3d_cli.render.notebook import props_html

        return props_html(self)


@dataclass(frozen=True)
class BoundsResult(Record):
    """One input's answer to ``p3d bounds``.

    Attributes
    ----------
    source : str
        The path or spec as the user gave it.
    format : str
        The mesh format, ``primitive`` or ``tessellated``.
    method : str
        ``vertices`` (projection of every vertex) or ``closed form``.
    bounds : Bounds
    faces : int
        Triangle (or tetrahedron) count; 0 for a primitive.
    warnings : tuple of CodedWarning
    """

    source: str
    format: str
    method: str
    bounds: Bounds
    faces: int = 0
    warnings: tuple[CodedWarning, ...] = field(default_factory=tuple)

    def __post_init__(self):
        object.__setattr__(self, "warnings", coded(self.warnings, self.source))

    # One step to the box's quantities.
    @property
    def min(self) -> np.ndarray:
        """``bounds.min``."""
        return self.bounds.min

    @property
    def max(self) -> np.ndarray:
        """``bounds.max``."""
        return self.bounds.max

    @property
    def size(self) -> np.ndarray:
        """``bounds.size``."""
        return self.bounds.size

    @property
    def center(self) -> np.ndarray:
        """``bounds.center``."""
        return self.bounds.center

    @property
    def diagonal(self) -> float:
        """``bounds.diagonal``."""
        return self.bounds.diagonal

    def _record(self) -> dict[str, Any]:
        return bounds_record(self)

    @property
    def warning_codes(self) -> tuple[str, ...]:
        """The stable code of each warning, in the same order (``p3d_cli.warning_codes``)."""
        return tuple(w.code for w in self.warnings)

    def _repr_html_(self) -> str:
        """In a notebook: the box's numbers, and the part with its box."""
        from p3d_cli.render.notebook import bounds_html

        return bounds_html(self)


INERTIA_CONVENTION = "positive tensor: Ixx = ∫(y²+z²) dm, Ixy = -∫xy dm"


def props_record(result: PropsResult) -> dict:
    """The JSON object of ``p3d props`` for one input (stable keys; numpy arrays as they are:
    ``PropsResult.to_dict`` gives plain values)."""
    p, f = result.properties, result.facts
    record = {
        "source": f.source,
        "format": f.format,
        "method": result.method,
        "faces": f.faces,
        "closed": f.closed,
        "bounding": f.bounding,
        "volume": p.volume,
        "signed_volume": -p.volume if f.wound_inward else p.volume,
        "mass": p.mass,
        "density": p.density,
        "center_of_mass": p.center_of_mass,
        "inertia": p.inertia,
        "inertia_origin": p.inertia_origin,
        "principal_moments": p.principal_moments,
        "principal_axes": p.principal_axes,
        "second_moments": p.second_moments,
        "principal_quaternion": p.principal_quaternion,
        "principal_rpy": p.principal_rpy,
        "bounds": None if f.bounds is None else {"min": f.bounds.min, "max": f.bounds.max},
        "coordinate_dtype": f.coordinate_dtype,
        "inertia_convention": INERTIA_CONVENTION,
        "warnings": [str(w) for w in result.warnings],
        "warning_codes": list(result.warning_codes),
        "uncertainty": result.uncertainty,
    }
    if p.about is not None:
        record["about"] = p.about
        record["inertia_about"] = p.inertia_about
    record.update(result.details)
    record["units"] = result.units
    if result.parts:
        record["parts"] = [props_record(part) for part in result.parts]
    return record


def bounds_record(result: BoundsResult) -> dict:
    """The JSON object of ``p3d bounds`` for one input (stable keys)."""
    b = result.bounds
    return {
        "source": result.source,
        "format": result.format,
        "method": result.method,
        "faces": result.faces,
        "min": b.min,
        "max": b.max,
        "size": b.size,
        "center": b.center,
        "diagonal": b.diagonal,
        "warnings": [str(w) for w in result.warnings],
        "warning_codes": list(result.warning_codes),
    }
