"""The library's three measurements, one call each: ``props``, ``bounds`` and ``check``.

Each takes "a thing" (a path, ``-``, a shape spec, a shape object, an ``(n, 3, 3)`` triangle
array, a ``(vertices, faces)`` pair, or a loaded ``MeshSource``), resolves it once
(``p3d_cli.measure.solid.as_solid``) and returns a frozen result. The command line calls exactly
these: ``p3d props`` is parse → ``props(...)`` → format.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any, BinaryIO, Iterable

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.geometry.placement import IDENTITY, Placement, scaling, then
from p3d_cli.measure.solid import as_solid, names_assembly_file
from p3d_cli.measure.solid_result import (declared_units, finish, measure_solid, scene_assembly, scene_record,
                                          solid_bounds)
from p3d_cli.results import BoundsResult, PropsResult

if TYPE_CHECKING:  # imported where used, so that props and bounds never load the checks
    from p3d_cli.mesh.solidity_report import SelfIntersections
    from p3d_cli.mesh.verdicts import CheckResult

#: The values of ``props(method=...)``.
METHODS = ("exact", "montecarlo")


def props(thing: Any, placement: Placement | None = None, *, method: str = "exact",
          density: float | None = None, mass: float | None = None, about=None,
          tessellate: int | None = None, samples: int | None = None, seed: int | None = None,
          tolerance: float | None = None, format: str | None = None,
          stdin: BinaryIO | None = None, units: str | None = None,
          output_units: str | None = None, intersections: bool = False, shells: bool = False) -> PropsResult:
    """Volume, mass, centre of mass, inertia and principal frame of a mesh or shape.

    Parameters
    ----------
    thing : str, os.PathLike, Shape, array_like, (vertices, faces) or MeshSource
        What to measure (see ``p3d_cli.measure.solid.as_solid``).
    placement : Placement, optional
        Scale, then rotate about the world origin, then translate the solid first.
    method : {"exact", "montecarlo"}
        ``exact``: divergence theorem or closed forms, with rounding-error bounds in
        ``uncertainty``. ``montecarlo``: sample the bounding box with an inside test, with
        standard errors (an independent check of a mesh you distrust).
    density, mass : float or str, optional
        Exclusive: mass per unit volume (default 1), or the total mass; bare numbers, or text
        with a unit (``"7.85 g/cm^3"``, ``"2.5 lb"``) when ``units`` is given.
    about : (3,) array_like, optional
        Also give the inertia about this point (in ``units``).
    tessellate : int, optional
        Exact method only: measure a round shape's inscribed polyhedron of this many segments.
    samples, seed, tolerance : optional
        Monte Carlo only: point count (default 100,000), random seed (default 0), or a target
        relative standard error of the volume that picks the count.
    format : str, optional
        Format name for a path, instead of guessing from content and extension.
    stdin : binary stream, optional
        What ``-`` reads.
    units : {"mm", "cm", "m", "in", "ft"}, optional
        The length unit of the mesh and of ``about`` and the placement's translation. With
        units, results are in SI (or ``output_units``) and ``result.units`` says which.
    output_units : str, optional
        ``"LENGTH,MASS"`` of the results, e.g. ``"mm,g"`` (default ``"m,kg"``).
    intersections : bool
        Also test a mesh exactly for self-intersections and for closed shells nested wound
        alike (``p3d_cli.measure.bodies``): warnings ``self-intersecting`` and ``nested-shells``. The
        test also runs, without being asked, when the inertia is not a solid's.
    shells : bool
        Measure each closed shell of a mesh (with the cavities inside it) as a part of an
        assembly: the bodies of a multi-body export (implies ``intersections``).

    A path to an assembly file (YAML with a ``parts:`` list, ``p3d_cli.measure.assembly.parts``) or an
    ``Assembly`` gives the whole, with each part's result in ``result.parts``.

    Returns
    -------
    PropsResult

    Raises
    ------
    P3DError
        ``UsageError`` for bad parameters, ``SpecError`` for a malformed spec, ``InputError``
        for an input that cannot be read.

    Examples
    --------
    >>> import p3d_cli as p3d
    >>> p3d.props("box:1,2,3").properties.volume
    48.0
    """
    placement = IDENTITY if placement is None else placement
    check_props_options(method, density, mass, tessellate, samples, seed, tolerance)
    from p3d_cli import units as unit_rules

    found = _assembly(thing)
    solid = None
    if found is None:
        # A scene file (glTF, 3MF, DAE, AMF) declares its unit, and one of several objects is an
        # assembly of them (p3d_cli.io.scene).
        solid = as_solid(thing, format=format, stdin=stdin)
        units = declared_units(solid, units, density, mass)
        found = scene_assembly(solid)
        if shells:
            from p3d_cli.measure.bodies import shells_assembly

            found, extra = shells_assembly(solid, found)
    if found is not None:
        from p3d_cli.measure.assembly.whole import assembly_props

        result = assembly_props(found, placement, units=units, output_units=output_units,
                                density=density, mass=mass, about=about, method=method,
                                tessellate=tessellate, samples=samples, seed=seed,
                                tolerance=tolerance)
        if shells:
            return dataclasses.replace(result, warnings=result.warnings + tuple(extra))
        return result if solid is None else scene_record(result, solid)
    density_given = density is not None
    system, density, mass = unit_rules.resolve(units, output_units, density, mass)
    user_placement = placement
    if system is not None:
        placement = then(placement, scaling(system.factor, system.factor_error))
        if about is not None:
            about = np.asarray(about, dtype=np.float64) * system.factor
    from_unit = system is not None and (density is not None or mass is not None)
    result = measure_solid(solid, placement, method=method, density=density,
                           mass=mass, about=about, tessellate=tessellate, samples=samples, seed=seed,
                           tolerance=tolerance, density_error=unit_rules.DENSITY_ROUNDING if from_unit else 0.0)
    result = finish(result, system, user_placement, density_given)
    if solid.mesh is not None and solid.mesh.tetrahedra is None and (
            intersections or "self-intersecting" in result.warning_codes):
        from p3d_cli.measure.bodies import with_solidity_warnings

        result = with_solidity_warnings(result, solid.mesh)
    return result


def _assembly(thing):
    """``thing`` as an ``Assembly`` when it is one or names an assembly file, else None; the
    assembly modules are imported only then (a mesh's run does not pay for them)."""
    import os

    if isinstance(thing, (str, os.PathLike)) or type(thing).__name__ == "Assembly":
        if type(thing).__name__ == "Assembly" or names_assembly_file(thing):
            from p3d_cli.measure.assembly.parts import find_assembly

            return find_assembly(thing)
    return None


def check_props_options(method, density, mass, tessellate, samples, seed, tolerance) -> None:
    """Refuse option combinations before any input is read."""
    if method not in METHODS:
        raise UsageError("method", f"unknown method {method!r}", "use exact or montecarlo")
    if density is not None and mass is not None:
        raise UsageError("mass, density", "both given; they are exclusive",
                         "give one: the other follows from the volume")
    if method == "exact" and (samples is not None or seed is not None or tolerance is not None):
        raise UsageError("samples, seed, tolerance", "given without method=montecarlo",
                         "add method=montecarlo, or drop them")
    if method == "montecarlo" and tessellate is not None:
        raise UsageError("tessellate", "given with method=montecarlo",
                         "Monte Carlo samples the exact shape; drop one of them")
    if samples is not None:
        from p3d_cli.measure.montecarlo import check_samples

        check_samples(samples)  # a limit, checked before any input is read


def bounds(thing: Any, placement: Placement | None = None, *, tessellate: int | None = None,
           format: str | None = None, stdin: BinaryIO | None = None, units: str | None = None,
           output_units: str | None = None) -> BoundsResult:
    """Exact axis-aligned bounds of a mesh or shape after placement.

    Meshes and polyhedral shapes by projecting every vertex; round shapes by closed forms.

    Parameters
    ----------
    thing, placement, tessellate, format, stdin, units, output_units
        As for ``props`` (bounds are in the output length unit when units are given).

    Returns
    -------
    BoundsResult

    Raises
    ------
    P3DError

    Examples
    --------
    >>> import p3d_cli as p3d
    >>> p3d.bounds("box:1,2,3").bounds.max.tolist()
    [1.0, 2.0, 3.0]
    """
    placement = IDENTITY if placement is None else placement
    found = _assembly(thing)
    if found is not None:
        from p3d_cli.measure.assembly.whole import assembly_bounds

        return assembly_bounds(found, placement, units=units, output_units=output_units, tessellate=tessellate)
    solid = as_solid(thing, format=format, stdin=stdin)
    units = declared_units(solid, units)
    if units is not None or output_units is not None:
        from p3d_cli.units import resolve

        system, _, _ = resolve(units, output_units)
        if system is not None:
            placement = then(placement, scaling(system.factor, system.factor_error))
    return solid_bounds(solid, placement, tessellate)


def check(thing: Any, *, require: Iterable[str] | None = None, min_volume: float | None = None,
          max_faces: int | None = None, format: str | None = None, stdin: BinaryIO | None = None,
          weld: float | None = None) -> CheckResult:
    """Is a mesh a clean solid? Closed, oriented, outward, manifold, no degenerate or duplicate faces.

    Parameters
    ----------
    thing : str, os.PathLike, array_like, (vertices, faces) or MeshSource
        A mesh (shapes are clean solids by construction and are refused).
    require : iterable of str, optional
        The checks that must pass (``p3d_cli.mesh.verdicts.CHECKS``; default all).
    min_volume : float, optional
        Also fail a mesh whose signed volume is below this (in metres³ for a file that
        declares its unit, as every length and volume of the result is; else mesh units³).
    max_faces : int, optional
        Also fail a mesh with more faces than this.
    format, stdin
        As for ``props``.
    weld : float, optional
        Merge vertices within this distance (in the file's units) before checking; the result's
        ``weld`` says how many were merged and the largest distance. Never done without it.

    Returns
    -------
    CheckResult
        ``ok``, the failed checks, and the counts and sample locations of every problem.

    Raises
    ------
    P3DError
    """
    from p3d_cli.mesh.verdicts import CHECKS, check_source

    required = tuple(CHECKS) if require is None else tuple(require)
    unknown = [name for name in required if name not in CHECKS]
    if unknown:
        raise UsageError("require", f"no check named {unknown[0]!r}", "checks are: " + ", ".join(CHECKS))
    assembly = _assembly(thing) if format is None else None
    if assembly is not None:   # each mesh part on its own (p3d_cli.measure.assembly.check)
        from p3d_cli.measure.assembly.check import check_assembly

        return check_assembly(assembly, check, required, min_volume, max_faces)
    solid = as_solid(thing, format=format, stdin=stdin)
    if solid.mesh is None:
        raise UsageError("thing", f"{solid.source} is a shape spec, a clean solid by construction",
                         "check mesh files")
    if weld is not None:
        from p3d_cli.mesh.weld import check_tolerance

        weld = check_tolerance(weld)
    # A file that declares its unit is reported in metres, as props and bounds report it.
    declared = solid.mesh.length_unit
    whole = check_source(solid.mesh, solid.source, required, min_volume, max_faces, weld, declared)
    if not solid.mesh.objects:
        return whole
    # A multi-object file: each object is checked on its own, and the whole (where objects
    # that touch or overlap show as shared edges or duplicate faces).
    parts = tuple((name, check_source(part, part.where, required, min_volume, max_faces, weld, declared))
                  for name, part in solid.mesh.objects)
    failed = whole.failed + tuple(f"{name}:{c}" for name, part in parts for c in part.failed)
    return dataclasses.replace(whole, failed=failed, parts=parts)


def self_intersections(thing: Any, *, format: str | None = None,
                       stdin: BinaryIO | None = None) -> SelfIntersections:
    """The face pairs of a mesh whose interiors cross or overlap, decided exactly.

    Faces that share an edge or a vertex, or touch without crossing, are never reported;
    crossings, coplanar overlaps and folds are, wherever the mesh sits (docs/method.md,
    "Self-intersections"). This is ``check(thing, require=["no-self-intersection"])``'s
    ``report.self_intersections``.

    Parameters
    ----------
    thing, format, stdin
        As for ``check``.

    Returns
    -------
    SelfIntersections
        ``count``, ``by_kind``, ``pairs`` (every pair of face indices), ``kinds`` and
        ``samples`` (the first pairs, with a point where each meets).

    Examples
    --------
    >>> import numpy as np
    >>> import p3d_cli as p3d
    >>> cube = p3d.Box(1, 1, 1).triangles()           # [-1, 1]^3
    >>> p3d.self_intersections(np.concatenate([cube, cube + 1])).count
    6
    """
    result = check(thing, require=["no-self-intersection"], format=format, stdin=stdin)
    return result.report.self_intersections
