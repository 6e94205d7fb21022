"""Measuring an assembly (``p3d_cli.measure.assembly.parts``): every part placed in one frame, then the whole.

Units: an assembly's ``units`` (or the caller's, for a file that names none) is the length
unit of its meshes and translations; a nested file without ``units`` inherits its parent's.
Every placement is carried into the output units by conjugating with the length factor ``f``
of the file it is written in (a uniform scale commutes with rotations and scales, so only the
translation changes: ``t -> f t``), and each leaf's mesh coordinates are scaled by ``f`` first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from fractions import Fraction
from typing import Iterator

import numpy as np

from p3d_cli.errors import InputError, P3DError, UsageError
from p3d_cli.geometry.placement import Placement, converted, scaling, then
from p3d_cli.measure.assembly.parts import Assembly, Part
from p3d_cli.results import BoundsResult, MassProperties, MeshFacts, PropsResult
from p3d_cli.units import DENSITY_ROUNDING, UnitSystem, exact_length, length_factor, parse_output_units


def _system(assembly: Assembly, units: str | None, output_units: str | None) -> UnitSystem | None:
    if assembly.units is not None and units is not None and units != assembly.units:
        raise UsageError("units", f"{units} given, but {assembly.source} says units: {assembly.units}",
                         "drop units=, or make them agree")
    top = assembly.units or units
    if top is None:
        if output_units is not None:
            raise UsageError("output_units", "given without units=", "say the assembly's length unit first")
        return None
    length, mass = parse_output_units(output_units)
    return UnitSystem(top, length, mass)


def _factor(units: str | None, system: UnitSystem | None) -> Fraction:
    """The exact length factor from ``units`` to the output unit (1 when either is unknown)."""
    if system is None or units is None:
        return Fraction(1)
    return exact_length(units) / exact_length(system.length)


@dataclass(frozen=True)
class Leaf:
    """A mesh or shape part as the whole assembly sees it.

    Attributes
    ----------
    part : Part
    placement : Placement
        Its whole placement, in the output frame.
    units : str or None
        The length unit of the file it is written in.
    name : str
        Its name path (``bracket/clip`` for a part of a nested assembly).
    density : float or None
        The density (in output units) of the nearest enclosing nested-assembly part that gives
        one: the default of this part when it gives none.
    group : tuple or None
        ``(where, mass)`` of the enclosing nested-assembly part that gives a ``mass`` (in
        output units): the parts under it are scaled together to that mass.
    """

    part: Part
    placement: Placement
    units: str | None
    name: str
    density: float | None = None
    group: tuple[str, float] | None = None


def leaves(assembly: Assembly, outer: Placement, system: UnitSystem | None,
           units: str | None = None, path: str = "", density: float | None = None,
           group: tuple[str, float] | None = None) -> Iterator[Leaf]:
    """Every mesh or shape part of ``assembly`` (nested ones too), as a ``Leaf``.

    A nested assembly's part may give a ``density`` (the default of its parts that give none)
    or a ``mass`` (its parts' total, which then may not give their own).
    """
    units = assembly.units or units
    factor = _factor(units, system)
    if system is None and assembly.units is not None:
        raise InputError(f"{assembly.source}: units", "a nested assembly has units, its parent none",
                         "give the top assembly its units: too")
    for part in assembly.parts:
        name = f"{path}{part.name}"
        own = converted(part.placement, factor)
        if group is not None and (part.density is not None or part.mass is not None):
            raise InputError(part.where, f"gives its own {'mass' if part.mass is not None else 'density'}, "
                             f"and {group[0]} gives the mass of the parts it holds",
                             "give the mass once: on the nested assembly or on its parts")
        try:
            if isinstance(part.thing, Assembly):
                d, m = _amounts(part, units, system, None, None)
                inner = (part.where, m) if m is not None else group
                yield from leaves(part.thing, then(own, outer), system, units, name + "/",
                                  density if d is None else d, inner)
                continue
            total = then(converted(part.placement, factor, coordinates=True), outer)
        except InputError:
            raise
        except P3DError as exc:
            raise InputError(f"{part.where}.{exc.where}", exc.what, exc.hint) from None
        yield Leaf(part, total, units, name, density, group)


def placed_parts(assembly: Assembly, placement: Placement, units: str | None = None) -> Iterator[tuple]:
    """Every mesh or shape part of ``assembly`` (nested ones too) as ``(solid, placement)``: the
    part resolved (``p3d_cli.measure.solid.Solid``) and its whole placement, its file's declared
    unit included, with coordinates in ``units`` (None: as written). For those that draw parts."""
    from p3d_cli.measure.solid import as_solid

    system = None if units is None else UnitSystem(units, units, "kg")
    for leaf in leaves(assembly, placement, system, units):
        solid = as_solid(leaf.part.thing)
        yield solid, declared_scale(solid, leaf.part, leaf.units, system, leaf.placement)


def _amounts(part: Part, units, system: UnitSystem | None, density, mass):
    from p3d_cli.units import resolve

    if part.density is not None or part.mass is not None:
        density, mass = part.density, part.mass
    output = None if system is None else f"{system.length},{system.mass}"
    try:
        _, density, mass = resolve(units, output, density, mass)
    except P3DError as exc:
        raise InputError(f"{part.where}.{exc.where}", exc.what, exc.hint) from None
    return density, mass


def assembly_props(assembly: Assembly, placement: Placement, *, units=None, output_units=None, density=None,
                   mass=None, about=None, method="exact", tessellate=None, samples=None, seed=None,
                   tolerance=None) -> PropsResult:
    """The whole assembly's ``PropsResult``, with each part's in ``parts``.

    ``density`` is the default of parts that give neither density nor mass; ``mass`` the
    whole's (for parts that give neither: the density follows from their total volume).

    Raises
    ------
    InputError, UsageError
    """
    from p3d_cli.geometry.inertia import combine_mass_properties, implausibilities
    from p3d_cli.measure.solid_result import finish, measure_solid
    from p3d_cli.measure.solid import as_solid

    system = _system(assembly, units, output_units)
    factor = 1.0 if system is None else system.factor
    outer = converted(placement, _factor(system.mesh_length if system else None, system))
    about_out = None if about is None else np.asarray(about, dtype=np.float64) * factor
    whole_mass = mass
    if whole_mass is not None and density is not None:
        raise UsageError("mass, density", "both given; they are exclusive", "give one")
    results: list[PropsResult] = []
    top = None if system is None else system.mesh_length
    groups: dict[str, tuple[float, list[int]]] = {}
    for leaf in leaves(assembly, outer, system, top):
        part = leaf.part
        if whole_mass is not None and (part.density is not None or part.mass is not None or leaf.group
                                       or leaf.density is not None):
            raise InputError(f"{(leaf.group or (part.where,))[0]}",
                             "gives its own density or mass, and the whole's mass is given",
                             "drop mass=, or the parts' own")
        if part.density is None and part.mass is None and leaf.density is not None:
            d, m = leaf.density, None           # a nested assembly's, already in output units
        else:
            d, m = _amounts(part, leaf.units, system, density, None)
        solid = as_solid(part.thing)
        total = declared_scale(solid, part, leaf.units, system, leaf.placement)
        shape_only = tessellate if solid.shape is not None else None
        from_unit = system is not None and (d is not None or m is not None)
        result = measure_solid(solid, total, method=method, density=d, mass=m, about=about_out,
                               tessellate=shape_only, samples=samples, seed=seed, tolerance=tolerance,
                               density_error=DENSITY_ROUNDING if from_unit else 0.0)
        result = finish(result, system, total, density_given=d is not None)
        if leaf.group is not None:
            groups.setdefault(leaf.group[0], (leaf.group[1], []))[1].append(len(results))
        results.append(replace(result, details={"name": leaf.name, **result.details}))
    if whole_mass is not None:
        _, target = _amounts(Part("", "", where=assembly.source), assembly.units or units, system, None,
                                whole_mass)
        groups[assembly.source] = (target, list(range(len(results))))
    for target, members in groups.values():
        masses = [results[i].properties.mass for i in members]
        k = target / sum(masses)
        k_error = _factor_error(target, masses, [results[i].uncertainty for i in members], system is not None)
        for i in members:
            p = results[i].properties
            results[i] = replace(results[i], properties=_rescaled(p, k),
                                 uncertainty=_rescaled_uncertainty(results[i].uncertainty, p, k, k_error))
    props = combine_mass_properties([r.properties for r in results], about_out)
    uncertainty = whole_uncertainty(results, props) if method == "exact" else None
    facts = MeshFacts(assembly.source, "assembly", sum(r.facts.faces for r in results), _closed(results),
                      _union([r.facts.bounds for r in results]))
    warnings = [w.named(r.details['name']) for r in results for w in r.warnings]
    if not warnings:
        warnings += implausibilities(props, facts.bounds, method)
    units_record = results[0].units
    details = {} if placement.is_identity else {"placement": placement.describe()}
    return PropsResult(facts, props, method, tuple(warnings), uncertainty, details, units_record, tuple(results))


def declared_scale(solid, part: Part, units: str | None, system: UnitSystem | None, total: Placement) -> Placement:
    """``total`` for a part whose file declares its own length unit (glTF, 3MF, DAE, AMF): its
    coordinates are in that unit, not the assembly's, so they are scaled from one to the other
    first.

    Raises
    ------
    InputError
        The assembly has no units, so the declared unit cannot be related to the others'.
    """
    declared = solid.mesh.length_unit if solid.mesh is not None else None
    if declared is None or declared == units:
        return total
    if system is None or units is None:
        raise InputError(part.where, f"{solid.where} declares its unit ({declared}), and the assembly has none",
                         "give the assembly its units (units: in the file, units= for inputs combined)")
    return then(scaling(*length_factor(declared, units)), total)


def _rescaled(p: MassProperties, k: float) -> MassProperties:
    """``p`` with its density (so mass and every moment of mass) multiplied by ``k``."""
    times = lambda a: None if a is None else a * k
    return replace(p, density=p.density * k, mass=p.mass * k, inertia=times(p.inertia),
                   inertia_origin=times(p.inertia_origin), principal_moments=times(p.principal_moments),
                   second_moments=times(p.second_moments), inertia_about=times(p.inertia_about))


def at_mass(result: PropsResult, mass: float) -> PropsResult:
    """``result`` with its density, so its mass and every moment of mass, scaled to ``mass`` (its
    parts' too, by the same factor: one density over them all, as ``mass=`` gives an assembly).
    Every stated bound grows with the factor and its own rounding, which is the measured mass's
    bound relative to it. ``result.properties.mass`` must be positive."""
    p = result.properties
    k = mass / p.mass
    k_error = _factor_error(mass, [p.mass], [result.uncertainty], False) if result.uncertainty is not None else 0.0
    parts = tuple(replace(r, properties=_rescaled(r.properties, k),
                          uncertainty=_rescaled_uncertainty(r.uncertainty, r.properties, k, k_error))
                  for r in result.parts)
    return replace(result, properties=_rescaled(p, k), parts=parts,
                   uncertainty=_rescaled_uncertainty(result.uncertainty, p, k, k_error))


def _factor_error(target: float, masses: list, bounds: list, converted: bool) -> float:
    """Relative error of ``k = target / Σ m``: the masses' bounds and the sum's rounding, the
    division's, and the target's own when it was converted from a unit."""
    if any(u is None or u.get("mass") is None for u in bounds):
        return math.inf
    unit = 2.0 ** -53
    total = abs(sum(masses))
    spread = sum(u["mass"] for u in bounds) + len(masses) * unit * sum(abs(m) for m in masses)
    return spread / total + unit + (DENSITY_ROUNDING if converted else 0.0) if total else math.inf


def _rescaled_uncertainty(u: dict | None, p: MassProperties, k: float, k_error: float = 0.0) -> dict | None:
    """Bounds of part ``p`` (before the change) whose density was multiplied by ``k`` (``k_error``
    off, relative): mass and inertia scale (and round once more), volume and centre do not."""
    if u is None or u.get("inertia") is None:
        return u
    eps = np.finfo(np.float64).eps
    grow = k * (1 + 4 * eps)
    return {**u, "mass": (u["mass"] + k_error * abs(p.mass)) * grow,
            "inertia": (u["inertia"] + k_error * np.abs(p.inertia)) * grow}


def whole_uncertainty(results, whole: MassProperties) -> dict | None:
    """A-priori bounds on the whole's volume, mass, centre and inertia, from the parts' bounds.

    First-order propagation through ``combine_mass_properties`` with absolute values, plus the
    rounding of its sums (``n + 4`` roundings of the sums of magnitudes): ``δM = Σ δmᵢ``; ``c =
    Σ mᵢ cᵢ / M`` moves by ``Σ (mᵢ δcᵢ + δmᵢ |cᵢ - c|) / M``; each parallel-axis term ``mᵢ (|dᵢ|² E -
    dᵢ dᵢᵀ)``, ``dᵢ = cᵢ - c``, by ``δmᵢ (|dᵢ|² E + |dᵢ||dᵢ|ᵀ) + mᵢ (2 |dᵢ|·δdᵢ E + δdᵢ|dᵢ|ᵀ +
    |dᵢ|δdᵢᵀ)`` with ``δdᵢ = δcᵢ`` (the whole's centre error ``δc`` adds ``M (2|δc|² E + 2 δc δcᵀ)``
    only: it cancels at first order). None when a part has no bound (Monte Carlo, or a part
    without volume).
    """
    bounds = [r.uncertainty for r in results]
    if not results or any(u is None or u.get("inertia") is None or u.get("mass") is None for u in bounds):
        return None
    eps = np.finfo(np.float64).eps
    rounding = (len(results) + 4) * eps
    parts = [r.properties for r in results]
    c = whole.center_of_mass
    total = abs(whole.mass)
    d_volume = sum(u["volume"] for u in bounds) + rounding * sum(abs(p.volume) for p in parts)
    d_mass = sum(u["mass"] for u in bounds) + rounding * sum(abs(p.mass) for p in parts)
    moved = sum(abs(p.mass) * u["center_of_mass"] + u["mass"] * np.abs(p.center_of_mass - c)
                for p, u in zip(parts, bounds))
    d_center = (moved + rounding * sum(abs(p.mass) * np.abs(p.center_of_mass) for p in parts)) / total
    d_center = d_center + np.spacing(np.abs(c))
    # A shift e of the whole's centre changes Σ mᵢ dᵢ dᵢᵀ by M e eᵀ only (Σ mᵢ dᵢ = 0): second
    # order. The parts' own centre errors enter at first order.
    d_inertia = total * (2 * (d_center @ d_center) * np.eye(3) + 2 * np.outer(d_center, d_center))
    for p, u in zip(parts, bounds):
        d = np.abs(p.center_of_mass - c)
        dd = u["center_of_mass"]
        m, dm = abs(p.mass), u["mass"]
        size = d @ d * np.eye(3) + np.outer(d, d)
        # The part's centre error to first order and (dd ddᵀ) to second, so that a bound that
        # knows a composed placement's rounding exactly is never undercut.
        d_inertia += (u["inertia"] + dm * size + m * (2 * (d @ dd) * np.eye(3) + np.outer(dd, d) + np.outer(d, dd))
                      + (m + dm) * ((dd @ dd) * np.eye(3) + np.outer(dd, dd)) + dm * (
                          2 * (d @ dd) * np.eye(3) + np.outer(dd, d) + np.outer(d, dd))
                      + rounding * (np.abs(p.inertia) + m * size))
    # Rounded up: the parts' bounds can be all but reached (a composed placement's rounding is
    # known exactly), so the float sums above must not round the whole's below its error.
    up = 1.0 + 2.0 ** -40
    return {"volume": d_volume * up, "mass": d_mass * up, "center_of_mass": d_center * up, "inertia": d_inertia * up}


def _closed(results) -> bool | None:
    flags = [r.facts.closed for r in results]
    if any(f is False for f in flags):
        return False
    return True if all(f is True for f in flags) else None


def _union(boxes):
    boxes = [b for b in boxes if b is not None]
    if not boxes:
        return None
    out = boxes[0]
    for b in boxes[1:]:
        out = out.union(b)
    return out


def assembly_bounds(assembly: Assembly, placement: Placement, *, units=None, output_units=None,
                    tessellate=None) -> BoundsResult:
    """The exact bounds of every placed part, and their union."""
    from p3d_cli.measure.solid_result import solid_bounds
    from p3d_cli.measure.solid import as_solid

    system = _system(assembly, units, output_units)
    outer = converted(placement, _factor(system.mesh_length if system else None, system))
    found = []
    for leaf in leaves(assembly, outer, system, None if system is None else system.mesh_length):
        solid = as_solid(leaf.part.thing)
        total = declared_scale(solid, leaf.part, leaf.units, system, leaf.placement)
        result = solid_bounds(solid, total, tessellate if solid.shape is not None else None)
        found.append(replace(result, warnings=tuple(w.named(leaf.name) for w in result.warnings)))
    methods = {r.method for r in found}
    from p3d_cli.geometry.bounding import checked_bounds

    with np.errstate(over="ignore"):
        union = _union([r.bounds for r in found])
    return BoundsResult(assembly.source, "assembly", methods.pop() if len(methods) == 1 else "mixed",
                        checked_bounds(assembly.source, union), sum(r.faces for r in found),
                        tuple(w for r in found for w in r.warnings))
