"""A link measured from its geometry: an assembly of its geoms (``p3d_cli.measure.props``).

Each collision (or visual) geom is one part, placed in the link frame by its own placement
(mesh scale, rotation, translation); the link's mass properties are the parts' summed with the
parallel-axis terms (``p3d_cli.geometry.inertia.combine_mass_properties``), in the description's units
(SI). Geoms that overlap are counted twice, as MuJoCo counts them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import RangeError, UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.measure import Assembly, Part
from p3d_cli.results import PropsResult
from p3d_cli.robots.model import Geom, Link


@dataclass(frozen=True)
class LinkGeometry:
    """A link's measured geometry.

    Attributes
    ----------
    result : PropsResult or None
        The whole link (its parts in ``result.parts``); None when it encloses no volume.
    solid : bool
        Every geom is a closed, outward-wound solid with volume (no warning was raised).
    problems : tuple of str
        Why it is not (each geom's warnings, named by the geom).
    stand_in : str or None
        What stands in for geometry that is not a solid (``open_mesh``): ``"thin shell"`` or
        ``"convex hull of collision[0], ..."``; None when the geometry is measured as it is.
    """

    result: PropsResult
    solid: bool
    problems: tuple[str, ...]
    stand_in: str | None = None


def link_assembly(link: Link, role: str, source: str) -> Assembly:
    """The link's ``role`` geometry as an assembly of parts in the link frame (in metres)."""
    geoms = link.geoms(role)
    # A geom of zero mass or density (MJCF: a massless visual) adds nothing to the link's mass;
    # but when every geom is massless (MuJoCo menagerie's visual class, density="0"), they are
    # the shape asked for, and weigh alike.
    massive = [g for g in geoms if g.mass != 0 and g.density != 0]
    weights = bool(massive)
    parts = tuple(Part(geom.where.rsplit(": ", 1)[-1], *_in_metres(geom),
                       density=geom.density if weights and geom.mass is None else None,
                       mass=geom.mass if weights else None, where=geom.where)
                  for geom in (massive or geoms))
    return Assembly(f"{source}: link {link.name!r}", parts)


def _in_metres(geom: Geom) -> tuple[object, Placement]:
    """The geom's solid and placement with its coordinates in metres, the description's unit: a
    mesh file that declares its own length unit (COLLADA's ``<unit meter>``, glTF's metres) is
    scaled from it first, in its own frame, before the geom's scale and placement."""
    from p3d_cli.measure import as_solid
    from p3d_cli.units import LENGTHS

    solid = as_solid(geom.thing)
    unit = solid.mesh.length_unit if solid.mesh is not None else None
    if unit is None:
        return solid.mesh if solid.mesh is not None else geom.thing, geom.placement
    k = LENGTHS[unit] / LENGTHS["m"]
    mesh = dataclasses.replace(solid.mesh, length_unit=None)  # now in metres, as the description
    if k == 1:
        return mesh, geom.placement
    p = geom.placement
    scale = np.full(3, k) if p.scale is None else np.asarray(p.scale, dtype=np.float64) * k
    return mesh, Placement(scale, p.rotation, p.translation)


def measure_link(link: Link, role: str, source: str, *, density: float | None = None,
                 mass: float | None = None, open_mesh: str = "refuse") -> LinkGeometry | None:
    """The link's mass properties from its ``role`` geometry (None: it has none).

    Parameters
    ----------
    density : float, optional
        kg/m³ for every geom (default 1 when no ``mass`` is given).
    mass : float, optional
        The link's whole mass, spread over its geoms by volume.
    open_mesh : {"refuse", "hull", "shell"}
        What stands in for geometry that bounds no solid (``p3d_cli.robots.open_mesh``):
        nothing (the result says why), each such mesh's convex hull, or a thin shell over the
        link's whole surface (needs ``mass``).

    Raises
    ------
    InputError
        A mesh that cannot be read.
    RangeError
        ``mass`` so large that the inertia overflows.
    MissingExtraError
        ``open_mesh="hull"`` without scipy.
    """
    if not link.geoms(role):
        return None
    assembly = link_assembly(link, role, source)
    geometry = _measured(assembly, link, role, source, density, mass)
    if geometry.solid or open_mesh == "refuse":
        return geometry
    if open_mesh == "shell":
        return _shell(assembly, link, source, mass, geometry)
    return _hulled(assembly, link, role, source, density, mass, geometry)


def _measured(assembly: Assembly, link: Link, role: str, source: str, density, mass) -> LinkGeometry:
    from p3d_cli.measure import props

    try:
        # Sizes near float64's limit overflow inside the closed forms: p3d reports them as one
        # RangeError, so numpy's warnings would only be noise.
        with np.errstate(all="ignore"):
            result = props(assembly, density=1.0 if density is None else density)
    except UsageError as exc:
        if exc.where != "parts":
            raise
        return LinkGeometry(None, False, ("the geometry encloses no volume (flat or empty)",))
    except RangeError as exc:  # a geom's own error names its spec: say whose geometry it is
        raise RangeError(f"{source}: link {link.name!r}: {role}", f"{exc.where}: {exc.what}", exc.hint) from None
    except OverflowError:
        raise RangeError(assembly.source, "a geometry's size overflows float64 in its moments",
                         "check the sizes and their unit (metres)") from None
    problems: list[str] = list(result.warnings)
    if result.facts.closed is False and not problems:
        problems.append("a mesh is not closed")
    if mass is not None and result.properties.mass > 0:
        result = _at_mass(result, mass, source, link)
    return LinkGeometry(result, not problems, tuple(problems))


def _at_mass(result: PropsResult, mass: float, source: str, link: Link) -> PropsResult:
    from p3d_cli.measure import at_mass

    # Every moment of mass is linear in the density: scale them all, and their bounds, to the
    # mass asked for.
    with np.errstate(all="ignore"):  # overflow is refused just below
        scaled = at_mass(result, mass)
    props = scaled.properties
    if not (np.isfinite(props.mass) and np.all(np.isfinite(props.inertia))):
        raise RangeError(f"{source}: link {link.name!r}", f"mass {mass!r} makes the inertia overflow float64",
                         "check the mass and its unit")
    return scaled


def _hulled(assembly: Assembly, link: Link, role: str, source: str, density, mass,
            first: LinkGeometry) -> LinkGeometry:
    """The link with each mesh that bounds no solid replaced by its convex hull."""
    from p3d_cli.io.source import MeshSource
    from p3d_cli.robots.open_mesh import hull_triangles

    results = first.result.parts if first.result is not None else ()
    parts, hulled = [], []
    for i, part in enumerate(assembly.parts):
        own = results[i] if i < len(results) else None
        clean = own is not None and not own.warnings and own.facts.closed is not False
        if isinstance(part.thing, MeshSource) and not clean:
            parts.append(dataclasses.replace(part, thing=hull_triangles(part.thing.triangles(), part.where)))
            hulled.append(part.name)
        else:
            parts.append(part)
    if not hulled:
        return first
    again = _measured(dataclasses.replace(assembly, parts=tuple(parts)), link, role, source, density, mass)
    # The problems stay those of the geometry itself: they say why a stand-in was used.
    return dataclasses.replace(again, problems=first.problems + again.problems,
                               stand_in=f"convex hull of {', '.join(hulled)}")


def _shell(assembly: Assembly, link: Link, source: str, mass, first: LinkGeometry) -> LinkGeometry:
    """The link as a thin shell of ``mass`` over its whole surface."""
    from p3d_cli.measure import as_solid
    from p3d_cli.robots.open_mesh import placed_triangles, shell_properties

    where = f"{source}: link {link.name!r}"
    if mass is None:
        return LinkGeometry(None, False, first.problems + ("a thin shell needs the link's mass (a surface has no "
                                                          "volume for a density)",), "thin shell")
    triangles = np.concatenate([placed_triangles(as_solid(part.thing), part.placement) for part in assembly.parts])
    properties = shell_properties(triangles, mass, where)
    if first.result is None:
        from p3d_cli.results import Bounds, MeshFacts, PropsResult

        bounds = Bounds(triangles.reshape(-1, 3).min(axis=0), triangles.reshape(-1, 3).max(axis=0))
        result = PropsResult(MeshFacts(where, "assembly", len(triangles), None, bounds), properties)
    else:
        # The solid's bounds and parts are not the shell's: a thin shell states none.
        result = dataclasses.replace(first.result, properties=properties, uncertainty=None, parts=())
    return LinkGeometry(result, True, first.problems, "thin shell")

