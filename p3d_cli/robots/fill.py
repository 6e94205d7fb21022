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

import dataclasses
import re
from dataclasses import dataclass, field

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.robots.emit import inertial_lines
from p3d_cli.robots.geometry import measure_link
from p3d_cli.robots.model import Link, Robot
from p3d_cli.robots.xmltree import Document


@dataclass
class FilledLink:
    """What ``fill_robot`` did with one link: ``status`` is ``filled`` or ``kept``; ``reason``
    says why a link was kept; ``mass``, ``center`` and ``inertia`` are what was written;
    ``stand_in`` what stood in for an open mesh (``open_mesh``: a thin shell, a convex hull)."""

    link: str
    status: str
    reason: str = ""
    mass: float | None = None
    center: object = None
    inertia: object = None
    stand_in: str | None = None


@dataclass
class FillResult:
    """The filled description's bytes, and one ``FilledLink`` per link.

    Attributes
    ----------
    data : bytes
        The description's new bytes (its own bytes when nothing in it changed).
    links : list of FilledLink
    files : dict of str to bytes
        Every file that changed, by path: the description, and the included files that hold
        bodies or links filled (MJCF ``<include>``, SDF ``<include>``).
    """

    data: bytes
    links: list[FilledLink] = field(default_factory=list)
    files: dict[str, bytes] = field(default_factory=dict)


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
    from p3d_cli.io.yaml_loader import read_yaml

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
               masses: dict | None = None, force: bool = False, principal: bool = False,
               open_mesh: str = "refuse") -> FillResult:
    """The description with each link's inertial computed from its ``role`` geometry.

    Parameters
    ----------
    robot : Robot
    role : {"collision", "visual"}
    density : float or str, optional
        kg/m³, or text with a unit. MJCF: the density of geoms that give neither their own
        ``density`` nor ``mass`` (default MuJoCo's, 1000 kg/m³).
    mass_from : {"declared"}, optional
        Keep each link's declared mass (only its centre and inertia are recomputed).
    masses : dict, optional
        Link name -> mass (kg, or text with a unit); wins over the others.
    force : bool
        Also fill links whose geometry is open, flat or inward-wound.
    principal : bool
        MJCF: write ``quat`` + ``diaginertia`` rather than ``fullinertia``.
    open_mesh : {"refuse", "hull", "shell"}
        What stands in for geometry that bounds no solid (``p3d_cli.robots.open_mesh``): the
        link is kept (default), or filled from each open mesh's convex hull, or as a thin shell
        (which needs its mass: declared with ``mass_from``, or in ``masses``).

    Raises
    ------
    UsageError
        No way to find a link's mass, a bad density or ``mass_from``.
    InputError
        A mesh that cannot be read.
    """
    from p3d_cli.robots.open_mesh import OPEN_MESH

    if open_mesh not in OPEN_MESH:
        raise UsageError("open_mesh", f"{open_mesh!r} is none of {', '.join(OPEN_MESH)}", "give shell, hull or refuse")
    if mass_from not in (None, "declared"):
        raise UsageError("mass_from", f"{mass_from!r} is not a mass source", "give mass_from=declared")
    rho = None if density is None else _quantity(density, "density", "density")
    if rho is None and robot.format == "mjcf":
        from p3d_cli.robots.mjcf import DEFAULT_DENSITY

        rho = DEFAULT_DENSITY  # MuJoCo's own: every MJCF geom has a density

    given = {name: _quantity(v, "mass", "masses") for name, v in (masses or {}).items()}
    unknown = sorted(set(given) - {link.name for link in robot.links})
    if unknown:
        raise UsageError("masses", f"names no link {unknown[0]!r}", "give the masses of links of this description")
    edits: dict[Document, dict[int, tuple[int, int, bytes]]] = {}
    report = []
    seen: dict[int, FilledLink] = {}
    for link in robot.links:
        # The copies of a replicated MJCF body share their element and geometry: measured once.
        filled = seen.get(id(link.node))
        if filled is None or link.name in given:
            filled = seen[id(link.node)] = _fill_link(robot, link, role, rho, mass_from, given, force, open_mesh)
        elif filled.link != link.name:
            filled = dataclasses.replace(filled, link=link.name)
        if filled.status == "filled":
            lines = inertial_lines(robot.format, filled.mass, filled.center, filled.inertia, principal)
            edit = None if _already(link, filled, lines) else _edit(link, lines)
            if edit is None:
                pass  # the element already says this (to rounding): left byte for byte, so a second run changes nothing
            elif isinstance(edit, str):
                filled = FilledLink(link.name, "kept", edit)
            else:
                # A replicated body (MJCF <replicate>) is one element for all its copies: one edit.
                edits.setdefault(link.node.doc, {})[edit[0]] = edit
        report.append(filled)
    files = {doc.path: doc.splice(list(spans.values())) for doc, spans in edits.items()}
    return FillResult(files.get(robot.doc.path, robot.data), report, files)


def _fill_link(robot: Robot, link: Link, role: str, rho, mass_from, given, force, open_mesh) -> FilledLink:
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
    geometry = measure_link(link, role, robot.path, density=rho if mass is None else None, mass=mass,
                            open_mesh=open_mesh)
    if geometry.result is None or (not geometry.solid and not force):
        what = "; ".join(geometry.problems)
        options = "" if open_mesh != "refuse" else "; open_mesh=shell (a thin shell) or open_mesh=hull (the " \
                                                   "convex hull) gives an answer"
        return FilledLink(link.name, "kept", f"geometry is not a closed solid ({what})" + options +
                          ("" if geometry.result is None else "; force fills it anyway"))
    p = geometry.result.properties
    if geometry.stand_in:
        reason = f"open mesh: filled from its {geometry.stand_in} ({'; '.join(geometry.problems)})"
    else:
        reason = "" if geometry.solid else "forced: " + "; ".join(geometry.problems)
    return FilledLink(link.name, "filled", reason, p.mass, p.center_of_mass, p.inertia, geometry.stand_in)


#: Numbers in an element's text, for comparing its form with what fill writes.
_NUMBER = re.compile(rb"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
#: How close declared numbers must be to the computed ones to be left as they are: a few
#: roundings (the same inertial reached by another road, e.g. from its declared mass).
SAME = 1e-12


def _already(link: Link, filled: FilledLink, lines: list[str]) -> bool:
    """Whether the link's inertial element is already what fill would write: the same form
    (element, attributes, layout, numbers aside) and the same numbers to ``SAME``."""
    node, declared = link.inertial_node, link.inertial
    if node is None or declared is None or node.expanded:
        return False
    old = node.doc.text[node.start:node.end]
    new = "\n".join(lines).encode()
    if b"".join(_NUMBER.sub(b"#", old).split()) != b"".join(_NUMBER.sub(b"#", new).split()):
        return False
    inertia = np.asarray(filled.inertia, dtype=np.float64)
    scale = float(np.abs(inertia).max()) or 1.0
    return bool(abs(declared.mass - filled.mass) <= SAME * abs(filled.mass)
                and np.all(np.abs(declared.center - np.asarray(filled.center)) <= SAME * (1 + np.abs(declared.center)))
                and np.all(np.abs(declared.inertia - inertia) <= SAME * scale))


def _indent_of(data: bytes, offset: int) -> bytes:
    """The whitespace that starts the line holding ``offset``."""
    line = data.rfind(b"\n", 0, offset) + 1
    i = line
    while i < offset and data[i] in b" \t":
        i += 1
    return data[line:i]


def _edit(link: Link, lines: list[str]) -> tuple[int, int, bytes] | str:
    """The edit (offsets in the link's document) that puts ``lines`` in place of the link's
    inertial, or as its first child; or why there is none (an element an entity brings in)."""
    doc = link.node.doc
    data = doc.text
    newline = doc.newline  # keep a Windows file's line endings
    node = link.inertial_node
    if node is not None:
        if node.expanded or node.doc is not doc:
            return "its <inertial> comes from an entity reference, which fill does not rewrite"
        indent = _indent_of(data, node.start)
        return node.start, node.end, (newline + indent).join(s.encode() for s in lines)
    if link.node.expanded:
        return "its element comes from an entity reference, which fill does not rewrite"
    own = _indent_of(data, link.node.start)
    first = next((c for c in link.node.children if not c.expanded), None)
    indent = _indent_of(data, first.start) if first is not None else own + b"  "
    body = b"".join(newline + indent + s.encode() for s in lines)
    if link.node.empty:  # <link name="x"/>: open it
        tag = link.node.tag.encode()
        return link.node.tag_end - 2, link.node.tag_end, b">" + body + newline + own + b"</" + tag + b">"
    return link.node.tag_end, link.node.tag_end, body


def write_fill(robot: Robot, result: FillResult, output: str | None = None) -> list[str]:
    """Write a fill's result to ``output``, or (None) every changed file over itself.

    Each file is written through ``p3d_cli.io.atomic.replacing``: a temporary file in the same
    folder, renamed over the target when complete, with the target's permissions. Every
    target is checked before any is written (a read-only or hard-linked one is refused).

    Returns
    -------
    list of str
        The paths written.

    Raises
    ------
    OutputError
        ``output`` is the description or another input (use ``output=None``, the in-place
        mode), or a target cannot be written.
    UsageError
        In place for a description that has no file of its own (expanded from xacro), or an
        ``output`` when inertials in included files changed too.
    """
    import os

    from p3d_cli.errors import OutputError
    from p3d_cli.io.atomic import destination, replacing, same_file

    what = "the filled description"
    if output is None:
        if robot.doc.path != robot.path:
            raise UsageError("in_place", f"{robot.path} is expanded by xacro, so its inertials cannot be written "
                             "back into it", "write the filled URDF to another file (output=)")
        order = sorted(result.files, key=lambda path: path == robot.path)  # the description last
        for path in order:
            destination(path, in_place=True, what=what)
        for path in order:
            with replacing(path, in_place=True, what=what) as f:
                f.write(result.files[path])
        return order
    others = sorted(set(result.files) - {robot.doc.path})
    if others:
        raise UsageError("output", f"filled inertials are in included files too ({', '.join(others)}), which "
                         "one output cannot hold", "rewrite each file in place (in_place=True)")
    inputs = description_files(robot)
    for source in inputs:
        if same_file(output, source):
            raise OutputError(output, f"{what} would overwrite the input {source}",
                              "give another path, or in_place=True to rewrite the description itself")
    with replacing(output, inputs=inputs, what=what) as f:
        f.write(result.data)
    return [os.fspath(output)]


def description_files(robot: Robot) -> list[str]:
    """Every file a description reads: itself, its included files, its meshes."""
    import os

    paths = {robot.path}
    for link in robot.links:
        if link.node.doc is not None:
            paths.add(link.node.doc.path)
        for geom in link.collision + link.visual:
            if os.path.sep in geom.thing or os.path.exists(geom.thing):
                paths.add(geom.thing)
    return sorted(p for p in paths if os.path.exists(p))
