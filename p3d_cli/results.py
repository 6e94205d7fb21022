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

import numpy as np

from p3d_cli.warning_codes import code_of


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

    @property
    def principal_quaternion(self) -> np.ndarray | None:
        """The principal frame as a unit quaternion ``[w, x, y, z]`` (``w >= 0``): the rotation
        taking the world axes to the principal axes (its matrix has the axes as columns, so it
        is MJCF's ``<inertial quat=...>``, and ``I = R diag(principal_moments) Rᵀ``)."""
        if self.principal_axes is None:
            return None
        from p3d_cli.geometry.rotation import matrix_quaternion

        return matrix_quaternion(self.principal_axes.T)

    @property
    def principal_rpy(self) -> np.ndarray | None:
        """The same rotation as ``principal_quaternion`` as URDF roll, pitch, yaw (radians)."""
        if self.principal_axes is None:
            return None
        from p3d_cli.geometry.rotation import matrix_rpy

        return matrix_rpy(self.principal_axes.T)


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
class PropsResult:
    """One input's answer to ``p3d props``.

    Attributes
    ----------
    facts : MeshFacts
    properties : MassProperties
    method : str
        ``exact`` (divergence theorem / closed form) or ``montecarlo``.
    warnings : tuple of str
        Plain-words warnings; ``warning_codes`` gives their stable codes.
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
    warnings: tuple[str, ...] = field(default_factory=tuple)
    uncertainty: dict | None = None
    details: dict = field(default_factory=dict)
    units: dict | None = None
    parts: tuple["PropsResult", ...] = field(default_factory=tuple)

    @property
    def warning_codes(self) -> tuple[str, ...]:
        """The stable code of each warning, in the same order (``p3d_cli.warning_codes``)."""
        return tuple(code_of(w) for w in self.warnings)

    def _repr_html_(self) -> str:
        """In a notebook: the numbers, and the part with its principal frame and inertia box."""
        from p3d_cli.render.notebook import props_html

        return props_html(self)


@dataclass(frozen=True)
class BoundsResult:
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
    warnings : tuple of str
    """

    source: str
    format: str
    method: str
    bounds: Bounds
    faces: int = 0
    warnings: tuple[str, ...] = field(default_factory=tuple)

    @property
    def warning_codes(self) -> tuple[str, ...]:
        """The stable code of each warning, in the same order (``p3d_cli.warning_codes``)."""
        return tuple(code_of(w) for w in self.warnings)

    def _repr_html_(self) -> str:
        """In a notebook: the box's numbers, and the part with its box."""
        from p3d_cli.render.notebook import bounds_html

        return bounds_html(self)
