"""A link measured from its geometry: an assembly of its geoms (``p3d_cli.assemble``).

Each collision (or visual) geom is one part, placed in the link frame by its own placement
(mesh scale, rotation, translation); the link's mass properties are the parts' summed with the
parallel-axis terms (``p3d_cli.inertia.combine_mass_properties``), in the description's units
(SI). Geoms that overlap are counted twice, as MuJoCo counts them.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from p3d_cli.assembly import Assembly, Part
import numpy as np

from p3d_cli.errors import RangeError, UsageError
from p3d_cli.placement import IDENTITY, Placement
from p3d_cli.results import MassProperties, PropsResult
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
    """

    result: PropsResult
    solid: bool
    problems: tuple[str, ...]


def link_assembly(link: Link, role: str, source: str) -> Assembly:
    """The link's ``role`` geometry as an assembly of parts in the link frame."""
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
    from p3d_cli.solid import as_solid
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
                 mass: float | None = None) -> LinkGeometry | None:
    """The link's mass properties from its ``role`` geometry (None: it has none).

    Parameters
    ----------
    density : float, optional
        kg/m³ for every geom (default 1 when no ``mass`` is given).
    mass : float, optional
        The link's whole mass, spread over its geoms by volume.

    Raises
    ------
    InputError
        A mesh that cannot be read.
    RangeError
        ``mass`` so large that the inertia overflows.
    """
    from p3d_cli.assemble import assembly_props

    if not link.geoms(role):
        return None
    assembly = link_assembly(link, role, source)
    try:
        # Sizes near float64's limit overflow inside the closed forms: p3d reports them as one
        # RangeError, so numpy's warnings would only be noise.
        with np.errstate(all="ignore"):
            result = assembly_props(assembly, IDENTITY, density=1.0 if density is None else density)
    except UsageError as exc:
        if exc.where != "parts":
            raise
        return LinkGeometry(None, False, ("the geometry encloses no volume (flat or empty)",))
    except RangeError as exc:  # a geom's own error names its spec: say whose geometry it is
        raise RangeError(f"{source}: link {link.name!r}: {role}", f"{exc.where}: {exc.what}", exc.hint) from None
    except OverflowError:
        raise RangeError(assembly.source, "a geometry's size overflows float64 in its moments",
                         "check the sizes and their unit (metres)") from None
    problems = list(result.warnings)
    if result.facts.closed is False and not problems:
        problems.append("a mesh is not closed")
    if mass is not None and result.properties.mass > 0:
        # Every moment of mass is linear in the density: scale them all to the mass asked for.
        with np.errstate(all="ignore"):  # overflow is refused just below
            props = scaled(result.properties, mass / result.properties.mass)
        if not (np.isfinite(props.mass) and np.all(np.isfinite(props.inertia))):
            raise RangeError(f"{source}: link {link.name!r}", f"mass {mass!r} makes the inertia overflow float64",
                             "check the mass and its unit")
        result = dataclasses.replace(result, properties=props)
    return LinkGeometry(result, not problems, tuple(problems))


def scaled(p: MassProperties, k: float) -> MassProperties:
    """``p`` with its density, so its mass and every moment of mass, multiplied by ``k``."""
    times = lambda a: None if a is None else a * k
    return dataclasses.replace(p, density=p.density * k, mass=p.mass * k, inertia=times(p.inertia),
                               inertia_origin=times(p.inertia_origin), principal_moments=times(p.principal_moments),
                               second_moments=times(p.second_moments), inertia_about=times(p.inertia_about))
