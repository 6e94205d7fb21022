"""Writing each link's ``<inertial>`` from its geometry, leaving the rest of the file as it was.

The new element replaces the bytes of the declared one (``p3d_cli.robots.xmltree`` keeps every
element's span), or goes in as the link's first child, indented like its siblings; nothing
else in the file changes (comments, order, whitespace, quoting).

The mass of each link comes from, in order: ``masses`` (link name -> kg, or text with a unit),
the declared mass (``mass_from="declared"``), or ``density`` (kg/m³, or text with a unit).
A link whose geometry is not a closed solid (open, flat, inward-wound, or missing) keeps its
declared inertial unless ``force`` (missing geometry always does: there is nothing to measure).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from p3d_cli.errors import InputError, UsageError
from p3d_cli.robots.emit import inertial_lines
from p3d_cli.robots.geometry import measure_link
from p3d_cli.robots.model import Link, Robot
from p3d_cli.robots.xmltree import _tag_end


@dataclass
class FilledLink:
    """What ``fill_robot`` did with one link: ``status`` is ``filled`` or ``kept``; ``reason``
    says why a link was kept; ``mass``, ``center`` and ``inertia`` are what was written."""

    link: str
    status: str
    reason: str = ""
    mass: float | None = None
    center: object = None
    inertia: object = None


@dataclass
class FillResult:
    """The filled description's bytes, and one ``FilledLink`` per link."""

    data: bytes
    links: list[FilledLink] = field(default_factory=list)


def _quantity(value, kind: str, name: str) -> float:
    from p3d_cli.units import has_unit, quantity_si

    if isinstance(value, str) and has_unit(value):
        return quantity_si(value, kind, name)
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise UsageError(name, f"{value!r} is not a number", "give a number (SI) or a quantity with a unit") from None
    if not x > 0 or x == float("inf"):
        raise UsageError(name, f"{value!r} is not positive and finite", "give a positive number")
    return x


def load_masses(path: str) -> dict[str, float]:
    """A YAML mapping of link names to masses (kg, or text with a unit: ``500 g``).

    Raises
    ------
    InputError
        Not readable, not a mapping, a value that is not a positive mass.
    """
    from p3d_cli.constraints.yaml_loader import read_yaml

    data = read_yaml(path, path, InputError)  # the scenes' hardened reader: duplicate keys, size, depth
    if not isinstance(data, dict):
        raise InputError(path, "is not a mapping of link names to masses", "write one line per link: forearm: 1.2 kg")
    out = {}
    for name, value in data.items():
        try:
            out[str(name)] = _quantity(value, "mass", "mass")
        except UsageError as exc:
            raise InputError(f"{path}: {name}", exc.what, exc.hint) from None
    return out


def fill_robot(robot: Robot, *, role: str = "collision", density=None, mass_from: str | None = None,
               masses: dict | None = None, force: bool = False, principal: bool = False) -> FillResult:
    """The description with each link's inertial computed from its ``role`` geometry.

    Parameters
    ----------
    robot : Robot
    role : {"collision", "visual"}
    density : float or str, optional
        kg/m³, or text with a unit.
    mass_from : {"declared"}, optional
        Keep each link's declared mass (only its centre and inertia are recomputed).
    masses : dict, optional
        Link name -> mass (kg, or text with a unit); wins over the others.
    force : bool
        Also fill links whose geometry is open, flat or inward-wound.
    principal : bool
        MJCF: write ``quat`` + ``diaginertia`` rather than ``fullinertia``.

    Raises
    ------
    UsageError
        No way to find a link's mass, a bad density or ``mass_from``.
    InputError
        A mesh that cannot be read.
    """
    if mass_from not in (None, "declared"):
        raise UsageError("mass_from", f"{mass_from!r} is not a mass source", "give mass_from=declared")
    rho = None if density is None else _quantity(density, "density", "density")
    given = {name: _quantity(v, "mass", "masses") for name, v in (masses or {}).items()}
    unknown = sorted(set(given) - {link.name for link in robot.links})
    if unknown:
        raise UsageError("masses", f"names no link {unknown[0]!r}", "give the masses of links of this description")
    edits: list[tuple[int, int, bytes]] = []
    report = []
    for link in robot.links:
        filled = _fill_link(robot, link, role, rho, mass_from, given, force)
        report.append(filled)
        if filled.status == "filled":
            lines = inertial_lines(robot.format, filled.mass, filled.center, filled.inertia, principal)
            edits.append(_edit(robot, link, lines))
    data = robot.data
    for start, end, text in sorted(edits, reverse=True):
        data = data[:start] + text + data[end:]
    return FillResult(data, report)


def _fill_link(robot: Robot, link: Link, role: str, rho, mass_from, given, force) -> FilledLink:
    if not link.geoms(role):
        return FilledLink(link.name, "kept", f"has no {role} geometry")
    mass = given.get(link.name)
    declared = link.inertial.mass if link.inertial is not None else None
    if mass is None and mass_from == "declared":
        if declared is not None and declared > 0:
            mass = declared
        elif rho is None:
            return FilledLink(link.name, "kept", "declares no positive mass to keep")
    if mass is None and rho is None:
        raise UsageError(f"{robot.path}: link {link.name!r}", "has no mass: no density, no declared mass kept "
                         "and no entry in masses", "give density=D, mass_from=declared or masses=TABLE")
    geometry = measure_link(link, role, robot.path, density=rho if mass is None else None, mass=mass)
    if geometry.result is None or (not geometry.solid and not force):
        what = "; ".join(geometry.problems)
        return FilledLink(link.name, "kept", f"geometry is not a closed solid ({what})" +
                          ("" if geometry.result is None else "; force fills it anyway"))
    p = geometry.result.properties
    return FilledLink(link.name, "filled", "" if geometry.solid else "forced: " + "; ".join(geometry.problems),
                      p.mass, p.center_of_mass, p.inertia)


def _indent_of(data: bytes, offset: int) -> bytes:
    """The whitespace that starts the line holding ``offset``."""
    line = data.rfind(b"\n", 0, offset) + 1
    i = line
    while i < offset and data[i] in b" \t":
        i += 1
    return data[line:i]


def _edit(robot: Robot, link: Link, lines: list[str]) -> tuple[int, int, bytes]:
    """The byte edit that puts ``lines`` in place of the link's inertial, or as its first child."""
    data = robot.data
    newline = b"\r\n" if b"\r\n" in data else b"\n"  # keep a Windows file's line endings
    node = link.inertial_node
    if node is not None:
        indent = _indent_of(data, node.start)
        return node.start, node.end, (newline + indent).join(s.encode() for s in lines)
    own = _indent_of(data, link.node.start)
    first = link.node.children[0] if link.node.children else None
    indent = _indent_of(data, first.start) if first is not None else own + b"  "
    body = b"".join(newline + indent + s.encode() for s in lines)
    tag_end = _tag_end(data, link.node.start)
    if data[tag_end - 2:tag_end] == b"/>":  # <link name="x"/>: open it
        tag = link.node.tag.encode()
        return tag_end - 2, tag_end, b">" + body + newline + own + b"</" + tag + b">"
    return tag_end, tag_end, body
