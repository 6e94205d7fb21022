"""One resolved solid measured: the step that single inputs and every part of an assembly share.

``p3d_cli.measure`` resolves what the user gave (units, assemblies) and calls these;
``p3d_cli.measure.assembly.whole`` calls them once per part.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.measure.solid import Solid
from p3d_cli.results import BoundsResult, PropsResult


def measure_solid(solid: Solid, placement: Placement, *, method: str, density, mass, about, tessellate,
                  samples, seed, tolerance, density_error: float = 0.0) -> PropsResult:
    """``solid``'s result by ``method``, everything already in the units of the result
    (``density_error``: the relative error of a converted density or mass, for the bounds)."""
    if method == "montecarlo":
        from p3d_cli.measure.montecarlo import montecarlo_props

        return montecarlo_props(solid, placement, samples=samples, seed=seed, tolerance=tolerance,
                                density=density, mass=mass, about=about)
    from p3d_cli.measure.exact import exact_props

    return exact_props(solid, placement, tessellate=tessellate, density=density, mass=mass, about=about,
                       density_error=density_error)


def finish(result: PropsResult, system, user_placement: Placement, density_given: bool = False) -> PropsResult:
    """Say the units, keep the user's placement in the record, add the plausibility warnings
    (``density_given``: the density was the user's, so the unit-slip warning applies)."""
    from p3d_cli.geometry.inertia import implausibilities
    from p3d_cli.units import MESH_UNITS, slip_warning

    details = dict(result.details)
    details.pop("placement", None)
    if not user_placement.is_identity:
        details["placement"] = user_placement.describe()
    warnings = list(result.warnings)
    if not warnings:
        warnings += implausibilities(result.properties, result.facts.bounds, result.method)
    if system is None and density_given and result.facts.bounds is not None:
        slip = slip_warning(float(result.facts.bounds.size.max()), result.properties.density)
        if slip is not None:
            warnings.append(slip)
    return dataclasses.replace(result, details=details, warnings=tuple(warnings),
                               units=MESH_UNITS if system is None else system.describe())


def solid_bounds(solid: Solid, placement: Placement, tessellate: int | None = None) -> BoundsResult:
    """Exact bounds of ``solid`` after ``placement`` (closed forms or vertex projection).

    Raises
    ------
    RangeError
        The bounds overflow float64 (``p3d_cli.geometry.bounding.checked_bounds``).
    """
    from p3d_cli.geometry.bounding import checked_bounds

    with np.errstate(over="ignore", invalid="ignore"):     # refused below, in one error
        result = _solid_bounds(solid, placement, tessellate)
    checked_bounds(solid.where, result.bounds)
    return result


def _solid_bounds(solid: Solid, placement: Placement, tessellate: int | None) -> BoundsResult:
    if solid.shape is not None:
        if tessellate is not None:
            from p3d_cli.measure.exact import shape_triangles

            triangles = shape_triangles(solid.shape, tessellate)
            return BoundsResult(solid.source, "tessellated", "vertices", placement.triangles_bounds(triangles),
                                len(triangles), solid.warnings)
        method = "vertices" if solid.shape.polyhedral else "closed form"
        return BoundsResult(solid.source, "primitive", method, placement.shape_bounds(solid.shape), 0,
                            solid.warnings)
    from p3d_cli.measure.exact import refuse_tessellate

    refuse_tessellate(solid, tessellate)
    return _mesh_bounds(solid, placement)


def _mesh_bounds(solid: Solid, placement: Placement) -> BoundsResult:
    mesh = solid.mesh
    if mesh.tetrahedra is not None:
        blocks: Iterable = (np.asarray(mesh.tetrahedra),)
    else:
        blocks = mesh.finite_blocks()
    try:
        box = placement.triangles_bounds(blocks)
    except InputError:
        raise  # the blocks' own (a non-finite coordinate), a ValueError too: as it is
    except ValueError:
        raise InputError(mesh.where, "the mesh has no faces", "export it again with its faces") from None
    return BoundsResult(solid.source, mesh.format, "vertices", box, mesh.face_count, tuple(mesh.warnings))




def declared_units(solid: Solid, units: str | None, density=None, mass=None) -> str | None:
    """The length unit to measure ``solid`` in: the one its file declares (glTF, 3MF, DAE,
    AMF), else ``units``.

    A declared unit acts as ``units=`` would: results are in SI (or ``output_units``), and a
    density or mass must carry its unit.

    Raises
    ------
    UsageError
        ``units`` disagrees with the file's unit, or a bare density or mass is given with it.
    """
    declared = solid.mesh.length_unit if solid.mesh is not None else None
    if declared is None:
        return units
    if units is not None and units != declared:
        raise UsageError("units", f"{units} given, but {solid.where} declares its unit: {declared}",
                         "drop units=, or make them agree")
    from p3d_cli.units import has_unit

    for name, value, example in (("density", density, "1000kg/m^3 or 1g/cm^3"), ("mass", mass, "2.5kg")):
        if units is None and value is not None and not has_unit(value):
            raise UsageError(name, f"{value} has no unit, and {solid.where} declares its length unit ({declared})",
                             f"write the unit, e.g. {example} (a bare number would be ambiguous)")
    return declared


def scene_assembly(solid: Solid):
    """A file of several objects (``MeshSource.objects``) as an assembly of them, else None."""
    mesh = solid.mesh
    if mesh is None or not mesh.objects:
        return None
    from p3d_cli.measure.assembly.parts import Assembly, Part

    parts = tuple(Part(name, source, where=source.where) for name, source in mesh.objects)
    return Assembly(solid.source, parts, mesh.length_unit)


def scene_record(result: PropsResult, solid: Solid) -> PropsResult:
    """An assembly result of a scene file, saying what the file is and how many objects it has."""
    mesh = solid.mesh
    facts = dataclasses.replace(result.facts, format=mesh.format, coordinate_dtype=mesh.coordinate_dtype)
    details = {**result.details, "objects": f"{len(mesh.objects)} {mesh.object_kind}"}
    warnings = tuple(mesh.warnings) + tuple(w for w in result.warnings if w not in mesh.warnings)
    return dataclasses.replace(result, facts=facts, details=details, warnings=warnings)
