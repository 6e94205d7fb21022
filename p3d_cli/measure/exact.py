"""The exact method: closed forms for shapes, the divergence theorem for meshes.

``exact_props`` takes a resolved ``Solid`` and returns its ``PropsResult``, with a-priori
rounding bounds (``exact_uncertainty``) and plain-words warnings for results that are not a
clean solid's (``mesh_warnings``).
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Iterator

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.geometry.inertia import breaks_triangle_inequality, inertia_from_second_moments, mass_properties
from p3d_cli.geometry.moments import check_range, shape_moments
from p3d_cli.geometry.placement import IDENTITY, Placement, prescaled
from p3d_cli.io.source import MeshSource
from p3d_cli.measure.solid import Solid
from p3d_cli.mesh.analysis import MeshAnalysis, analyze
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.results import Bounds, MassProperties, MeshFacts, Moments, PropsResult
from p3d_cli.shapes import SHAPES
from p3d_cli.warning_codes import CodedWarning

#: A float32 file whose coordinate spacing exceeds this fraction of the part's size is
#: coarse: the file itself, not the arithmetic, limits the accuracy (docs/method.md,
#: "Float32 input").
COARSE_FLOAT32 = 1e-6


def exact_props(solid: Solid, placement: Placement = IDENTITY, *, tessellate: int | None = None,
                density: float | None = None, mass: float | None = None, about=None,
                density_error: float = 0.0) -> PropsResult:
    """Mass properties of a shape (closed forms, or its tessellated stand-in) or of a mesh.

    Parameters
    ----------
    solid : Solid
    placement : Placement
        Scale, rotate and move the solid: its moments are placed by eq. 9 and ``R C Rᵀ`` from
        the unplaced integrals, and the bounds become the placed solid's.
    tessellate : int, optional
        Replace a round shape by an inscribed polyhedron of this many segments (a polyhedral
        shape is replaced by its own faces, which changes nothing). Not for meshes.
    density, mass : float, optional
        Exclusive; default density 1.
    about : (3,) array_like, optional
        Extra reference point for the inertia.
    density_error : float, optional
        Relative error of ``density`` or ``mass`` (a unit conversion's rounding,
        ``p3d_cli.units.DENSITY_ROUNDING``), carried into the bounds.

    Raises
    ------
    UsageError, InputError
        ``RangeError`` (an ``InputError``) when a result would overflow or underflow float64.
    """
    with np.errstate(all="ignore"):  # out-of-range results are caught by check_range instead
        result = _exact_props(solid, placement, tessellate, density, mass, about)
    if result.uncertainty is None or (density_error == 0 and mass is None):
        return result
    moments_error = result.uncertainty["volume"]
    return dataclasses.replace(result, uncertainty=material_errors(
        result.uncertainty, result.properties, density_error, moments_error if mass is not None else None))


def material_errors(uncertainty: dict, props: MassProperties, density_error: float,
                    volume_error: float | None = None) -> dict:
    """Bounds grown by the density's relative error: ``density_error`` (a converted density or
    mass), plus, when the density follows from a given mass (``volume_error`` is then the
    volume's bound), the volume's relative error and the division's rounding. Mass and every
    moment of mass are linear in the density, so each grows by that fraction of itself."""
    rel = density_error
    if volume_error is not None and props.volume != 0:
        rel += volume_error / abs(props.volume) + _UNIT
    if rel == 0 or uncertainty.get("mass") is None:
        return uncertainty
    out = {**uncertainty, "mass": uncertainty["mass"] + rel * abs(props.mass) * _UP}
    if uncertainty.get("inertia") is not None and props.inertia is not None:
        out["inertia"] = uncertainty["inertia"] + rel * np.abs(props.inertia) * _UP
    return out


#: Unit roundoff, and a factor that rounds a bound's own arithmetic upward.
_UNIT = 2.0 ** -53
_UP = 1.0 + 2.0 ** -40


def _exact_props(solid: Solid, placement: Placement, tessellate, density, mass, about) -> PropsResult:
    details: dict = {} if placement.is_identity else {"placement": placement.describe()}
    if solid.shape is None:
        refuse_tessellate(solid, tessellate)
        result = _mesh_props(solid, placement, density, mass, about)
    elif tessellate is not None:
        details["tessellate"] = tessellate
        triangles = shape_triangles(solid.shape, tessellate)
        unplaced = triangle_moments(triangles)
        moments = placement.moments(unplaced)
        check_range(solid.source, unplaced, moments)
        props = mass_properties(moments, density=density, mass=mass, about=about, where=solid.source)
        facts = MeshFacts(solid.source, "tessellated", len(triangles), True, placement.triangles_bounds(triangles))
        result = PropsResult(facts, props, "exact", solid.warnings, exact_uncertainty(moments, props))
    else:
        unplaced = shape_moments(solid.shape, solid.source)
        moments = placement.moments(unplaced)
        check_range(solid.source, unplaced, moments)
        props = mass_properties(moments, density=density, mass=mass, about=about, where=solid.source)
        facts = MeshFacts(solid.source, "primitive", 0, None, placement.shape_bounds(solid.shape))
        result = PropsResult(facts, props, "exact", solid.warnings, None)
    return dataclasses.replace(result, details={**result.details, **details})


def _mesh_props(solid: Solid, placement: Placement, density, mass, about) -> PropsResult:
    mesh = solid.mesh
    placed_bounds = None
    if not placement.is_identity:
        mesh, placed_bounds = watch_bounds(mesh, placement)
    found = analyze(mesh, mesh.where, rescale=True)
    check_range(solid.source, found.moments, found.moments)
    facts = mesh_facts(solid, found)
    warnings = list(solid.warnings) + list(mesh.warnings) + mesh_warnings(found.moments, facts)
    moments = found.moments
    if not moments.is_empty and moments.volume < 0:
        # Wound inward: measure the solid the faces enclose. Every signed integral flips with
        # the winding, so the volume and the central second moments change sign together
        # (docs/method.md, "Inward-wound meshes"); the centre does not move.
        moments = Moments(-moments.volume, moments.center, -moments.central, moments.errors)
        facts = dataclasses.replace(facts, wound_inward=True)
    if found.inverted_tetrahedra:
        warnings.append(CodedWarning(f"{found.inverted_tetrahedra} of {found.face_count} tetrahedra are listed "
                                     "inside out (negative orientation); each was counted with its positive "
                                     "volume", "inverted-tetrahedra"))
    if placed_bounds is not None or found.scale_exponent:
        # A part integrated scaled by 2ᵏ (too small or too large for float64's comfortable
        # range) is scaled back together with the placement, so that a tiny part scaled up
        # (or a huge one down) never passes through an under- or overflowing value.
        total = prescaled(placement, -found.scale_exponent, solid.source)
        unplaced, moments = moments, total.moments(moments)
        check_range(solid.source, unplaced, moments)
        if placed_bounds is not None:
            facts = dataclasses.replace(facts, bounds=placed_bounds())
    props = mass_properties(moments, density=density, mass=mass, about=about, where=solid.source)
    return PropsResult(facts, props, "exact", tuple(warnings), exact_uncertainty(moments, props))


def watch_bounds(mesh: MeshSource, placement: Placement) -> tuple[MeshSource, Callable[[], Bounds | None]]:
    """``mesh`` with its blocks also projected as they stream past, and a getter for the bounds.

    One pass serves both the integrals and the placed bounds, so standard input (which reads
    once) and large files are not read twice.
    """
    seen: list[Bounds] = []
    if mesh.tetrahedra is not None:
        tetrahedra = np.asarray(mesh.tetrahedra)
        return mesh, lambda: placement.triangles_bounds(tetrahedra)

    def blocks() -> Iterator[np.ndarray]:
        seen.clear()
        for block in mesh.read_blocks():
            if len(block):
                seen.append(placement.triangles_bounds(block))
            yield block

    def bounds() -> Bounds | None:
        if not seen:
            return None
        return Bounds(np.min([b.min for b in seen], axis=0), np.max([b.max for b in seen], axis=0))

    # Another read_blocks: the kernels' indexed road (which reads the vertices and faces, not
    # the blocks) is not taken for it (MeshSource.indexed_arrays), so every block streams past.
    return dataclasses.replace(mesh, read_blocks=blocks), bounds


def solid_moments(solid: Solid) -> Moments:
    """The unplaced volume moments of a shape (closed forms) or a mesh (one analysis pass)."""
    if solid.shape is not None:
        return shape_moments(solid.shape, solid.source)
    return analyze(solid.mesh, solid.mesh.where).moments


def mesh_facts(solid: Solid, found: MeshAnalysis) -> MeshFacts:
    """What the analysis of ``solid``'s mesh found, for the record."""
    mesh = solid.mesh
    return MeshFacts(solid.source, mesh.format, found.face_count, found.closed, found.bounds,
                     mesh.coordinate_dtype, found.bounding)


def shape_triangles(shape, tessellate: int) -> np.ndarray:
    """The polyhedron standing in for ``shape``: its own faces, or ``tessellate`` segments."""
    if shape.polyhedral:
        return shape.triangles()
    return shape.tessellate(tessellate)


def refuse_tessellate(solid: Solid, tessellate: int | None) -> None:
    """``tessellate`` applies to shapes only: a mesh is already polyhedral."""
    if tessellate is not None:
        round_names = ", ".join(n for n, c in SHAPES.items() if not c.polyhedral)
        raise UsageError("tessellate", f"{solid.source} is a mesh, already polyhedral",
                         f"tessellate= applies to shape specs ({round_names})")


def mesh_warnings(moments: Moments, facts: MeshFacts) -> list[CodedWarning]:
    """Plain-words warnings for results that are not a clean solid's, each a ``CodedWarning``
    (``p3d_cli.warning_codes``: open, flat, inward, self-intersecting, coarse-float32)."""
    out: list[CodedWarning] = []
    if facts.closed is False and facts.bounding:
        out.append(CodedWarning("mesh is non-manifold but bounding (some edge is used by more than two faces, "
                                "but every edge is used as often in each direction, vertices matched by exact "
                                "coordinates): the faces bound a solid, and these numbers are its own, "
                                "independent of the origin", "non-manifold"))
    elif facts.closed is False:
        out.append(CodedWarning("mesh is not closed (some edge is not shared by exactly two faces in opposite "
                   "directions, vertices matched by exact coordinates): an open surface has no "
                   "well-defined volume, and these numbers depend on the formula and the origin "
                   "(p3d sums signed tetrahedra from the world origin)", "open"))
    if moments.is_empty:
        out.append(CodedWarning("mesh encloses no volume (flat or degenerate): centre of mass and inertia are "
                                "undefined", "flat"))
    elif moments.volume < 0:
        what = "closed but wound inward" if facts.closed else "wound mostly inward"
        out.append(CodedWarning(f"signed volume is negative: the mesh is {what} (faces point into the solid); "
                                "the volume, mass and inertia reported are the enclosed solid's (positive; "
                                "signed_volume keeps the sign); reverse the face winding to fix", "inward"))
    if not moments.is_empty and facts.bounding:
        central = moments.central if moments.volume > 0 else -moments.central
        principal = np.linalg.eigvalsh(inertia_from_second_moments(central))
        if breaks_triangle_inequality(principal):
            out.append(CodedWarning("inertia is not a solid's (a principal moment is negative or breaks the "
                                    "triangle inequality): the mesh probably intersects itself",
                                    "self-intersecting"))
    coarse = _coarse_float32(facts)
    if coarse:
        out.append(coarse)
    return out


def _coarse_float32(facts: MeshFacts) -> CodedWarning | None:
    if facts.coordinate_dtype != "float32" or facts.bounds is None:
        return None
    extent = float(np.abs(np.concatenate([facts.bounds.min, facts.bounds.max])).max())
    size = facts.bounds.diagonal
    spacing = extent * 2.0 ** -23
    if size > 0 and spacing > COARSE_FLOAT32 * size:
        return CodedWarning(f"coordinates are float32 and the part lies far from the origin: the file "
                            f"resolves only {spacing:.3g} ({spacing / size:.2g} of the part's size); the "
                            "file's precision, not p3d's arithmetic, limits these results; export in "
                            "float64 (ASCII or double PLY) or nearer the origin", "coarse-float32",
                            spacing / size)
    return None


def exact_uncertainty(moments: Moments, props: MassProperties) -> dict | None:
    """A-priori rounding bounds of the exact method, mapped to the reported quantities."""
    errors = moments.errors
    if errors is None:
        return None
    out: dict = {"volume": errors.volume}
    if moments.is_empty:
        out.update(center_of_mass=None, inertia=None)
        return out
    density = abs(props.density)
    central = errors.central * density
    inertia = np.abs(np.trace(central)) * np.eye(3) + central
    # The last roundings happen after the sums: the centre is ``origin + offset`` (half an ulp
    # of the centre, which dominates far from the world origin: nothing finer is representable),
    # and mass, second moments and ``tr(S) E - S`` round a few more times.
    eps = np.finfo(np.float64).eps
    second = np.abs(props.second_moments)
    out["center_of_mass"] = errors.center + np.spacing(np.abs(props.center_of_mass))
    out["inertia"] = inertia + 4 * eps * (np.trace(second) * np.eye(3) + second)
    out["mass"] = errors.volume * density + float(np.spacing(abs(props.mass)))
    return out
