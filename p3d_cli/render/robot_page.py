"""``p3d robot check --report html:DIR``: each link's geometry with its declared and computed
inertia drawn together, flagged links first (docs/render.md, "Robot links").

One row per link (``p3d_cli.render.pages``): the verdict, each problem with its rule, the
notes, the numbers, and a picture of the link's geometry in the link frame with two equivalent
uniform boxes (or ellipsoids: ``shape="ellipsoid"``), each the solid of uniform density with the
same mass and principal moments (``overlays.equivalent_half_extents``), on its principal axes and
centred on its centre of mass (marked):

- **declared** (``COLOURS["declared"]``, raspberry, drawn wide): the description's mass, centre of
  mass and tensor;
- **computed** (``COLOURS["inertia"]``, teal, drawn narrow on top, the colour of ``p3d render
  --show inertia``): the geometry ``check_robot`` compared with, at the declared mass.

Two inertias that agree give one box (a teal line with a raspberry rim); a tensor about the
wrong axes gives a box turned; a wrong mass unit, a box far too small or large; a centre of mass
in the wrong frame, a box elsewhere. Lines inside the part are drawn too, half as wide.

Failed links come first, then passed links, then massless frames, each group in the
description's order. The page is ``pages.write_html``'s: inline CSS, no script, no resource from
the network, pictures in ``images/`` beside it.
"""

from __future__ import annotations

import dataclasses
import html
import os
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import P3DError, UsageError
from p3d_cli.render.overlays import COLOURS, Layer
from p3d_cli.render.pages import PICTURE_SIZE, Row

#: What ``shape`` may be: the uniform solid drawn for an inertia.
SHAPES = ("box", "ellipsoid")
#: Line widths (pixels at 800 x 600): the declared box under the computed one, wider, so that
#: where the two coincide both show.
DECLARED_WIDTH, COMPUTED_WIDTH = 7, 3
#: A box is left out of a picture that would have to span more than this many times its size and
#: the geometry's (a centre of mass at 1e300 m: the picture would show neither).
FAR = 1e6
#: A box smaller than this part of everything drawn is circled (a mass in grams declares one
#: about 30 times too small).
SMALL = 1 / 25
COMMAND = "p3d robot check"
#: The camera's azimuth and elevation, degrees (``p3d_cli.render.camera``): off the isometric
#: direction, where the near and far corners of a box on the link axes (any diagonal inertia)
#: fall on one point and the box reads as a flat hexagon.
VIEW = (30.0, 20.0)


@dataclass(frozen=True)
class _Inertia:
    """What ``overlays.inertia_layer`` reads of a ``MassProperties``."""

    mass: float
    center_of_mass: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray


def declared_inertia(inertial) -> _Inertia | None:
    """The declared inertial (``robots.model.Inertial``) in principal form; None when its mass or
    tensor is not finite, or its mass not positive (no box can be drawn)."""
    if inertial is None:
        return None
    mass, tensor = inertial.mass, np.asarray(inertial.inertia, dtype=np.float64)
    if not (np.isfinite(mass) and mass > 0 and np.all(np.isfinite(tensor)) and np.all(np.isfinite(inertial.center))):
        return None
    scale = max(float(np.abs(tensor).max()), 1e-300)
    unit = tensor / scale  # scaled before the sum, which would overflow near float64's limit
    moments, vectors = np.linalg.eigh(0.5 * (unit + unit.T))
    with np.errstate(over="ignore"):  # inf moments: no box is drawn (inertia_layers)
        moments = moments * scale
    return _Inertia(float(mass), np.asarray(inertial.center, dtype=np.float64), moments, vectors.T)


def computed_inertia(check):
    """The mass properties of the geometry ``check`` (a ``LinkCheck``) was compared with, at the
    declared mass; None when it was compared with none, or its geometry bounds no solid (the
    volume of an open mesh means nothing, and check did not use it)."""
    measured = check.measured
    if measured is None or measured.result is None or not measured.solid:
        return None
    properties = measured.result.properties
    if properties.principal_moments is None or not properties.mass > 0:
        return None
    return properties


def inertia_layers(declared, computed, shape: str = "box", triangles=None) -> list[Layer]:
    """The declared and the computed layer (either may be None: left out), in drawing order; a
    box whose size overflows float64, or that lies too far (``FAR``) from the link frame's origin
    and the geometry (``triangles``), is left out too."""
    from p3d_cli.render.overlays import equivalent_half_extents, inertia_layer, number

    layers = []
    for key, properties, width, name in (("declared", declared, DECLARED_WIDTH, "declared"),
                                         ("inertia", computed, COMPUTED_WIDTH, "computed")):
        with np.errstate(all="ignore"):
            layer = None if properties is None else inertia_layer(properties, shape)
            half = None if properties is None else equivalent_half_extents(properties, shape)
        if layer is None or half is None or not np.all(np.isfinite(layer.segments)) \
                or _too_far(layer.segments, triangles):
            continue
        size = " x ".join(number(2 * h) for h in half)
        label = f"{name}: {shape} {size} m"
        layers.append(dataclasses.replace(layer, key=key, label=label, width=width, xray=True,
                                          points=np.asarray(properties.center_of_mass, dtype=np.float64)[None]))
    return layers


def _size(points: np.ndarray) -> float:
    points = points.reshape(-1, 3)
    return float((points.max(axis=0) - points.min(axis=0)).max()) if len(points) else 0.0


def _too_far(segments: np.ndarray, triangles) -> bool:
    reference = np.zeros((1, 3)) if triangles is None else np.concatenate([np.zeros((1, 3)),
                                                                           triangles.reshape(-1, 3)])
    with np.errstate(all="ignore"):
        span = _size(np.concatenate([reference, segments.reshape(-1, 3)]))
        own = max(_size(segments), _size(reference), 1e-300)
    return not span <= FAR * own


def _circled(layers: list[Layer], triangles: np.ndarray) -> list[Layer]:
    """``layers`` with a ring around each box too small to find at a glance."""
    span = _size(np.concatenate([triangles.reshape(-1, 3)] + [layer.segments.reshape(-1, 3) for layer in layers]))
    out = []
    for layer in layers:
        out.append(dataclasses.replace(layer, ring=True) if _size(layer.segments) < SMALL * span else layer)
    return out


def _drawn_role(link, check, role: str) -> str | None:
    """Whose geometry the picture shows: the one compared with, else the one asked for (auto:
    collision, then visual)."""
    if check.role is not None:
        return check.role
    roles = ("collision", "visual") if role == "auto" else (role,)
    return next((r for r in roles if link.geoms(r)), None)


def link_picture(robot, link, check, *, shape: str = "box", role: str = "auto", view=VIEW, size=PICTURE_SIZE):
    """The picture of one link (``Picture``) and what it leaves out, in words.

    The link's geometry (the one compared with) in the link frame, the declared and the computed
    inertia as ``shape``; None when there is nothing to draw (no geometry, no usable inertial).
    An unreadable mesh gives a picture without geometry and a note, not an error.
    """
    from p3d_cli.render.camera import make_camera
    from p3d_cli.render.compose import compose
    from p3d_cli.render.picture import check_size

    width, height = check_size(size)
    notes = []
    drawn = _drawn_role(link, check, role)
    triangles = np.zeros((0, 3, 3))
    if drawn is not None:
        from p3d_cli.render.geometry import scene_triangles
        from p3d_cli.robots.geometry import link_assembly

        try:
            triangles = scene_triangles(link_assembly(link, drawn, robot.path)).triangles
        except P3DError as error:
            notes.append(f"its {drawn} geometry is not drawn: {error.message}")
    declared = declared_inertia(link.inertial)
    computed = computed_inertia(check)
    if link.inertial is not None and declared is None:
        notes.append(f"no declared {shape}: the mass is not positive, or a number is not finite")
    if computed is None and check.measured is not None and not check.measured.solid:
        notes.append(f"no computed {shape}: the geometry is not a closed solid")
    layers = _circled(inertia_layers(declared, computed, shape, triangles), triangles)
    for key, name, properties in (("declared", "declared", declared), ("inertia", "computed", computed)):
        if properties is not None and not any(layer.key == key for layer in layers):
            notes.append(f"the {name} {shape} is not drawn: it is too large, or too far from the link frame's "
                         "origin and its geometry, to show in one picture with them")
    if not len(triangles) and not layers:
        return None, "; ".join(notes + ["nothing to draw: no geometry and no declared inertia"])
    title = f"{link.name}  ({drawn}, {len(triangles):,} triangles)" if len(triangles) else f"{link.name}  (no geometry)"
    azimuth, elevation = view
    picture = compose(triangles, make_camera(None, azimuth, elevation), (width, height), layers, title,
                      f"link frame, azimuth {azimuth:g}, elevation {elevation:g}")
    return picture, "; ".join(notes)


def _vector(values, digits: int = 6) -> str:
    return "(" + ", ".join(f"{float(v) + 0.0:.{digits}g}" for v in values) + ")"


def _tensor(inertia) -> tuple[str, str]:
    """``ixx iyy izz`` and ``ixy ixz iyz``, as a description writes them."""
    i = np.asarray(inertia, dtype=np.float64)
    text = lambda values: " ".join(f"{float(v) + 0.0:.6g}" for v in values)
    return text((i[0, 0], i[1, 1], i[2, 2])), text((i[0, 1], i[0, 2], i[1, 2]))


def link_numbers(link, check, shape: str = "box") -> dict:
    """The numbers shown beside a link's picture (SI units): each quantity as a (declared,
    computed) pair, then the comparison's own numbers."""
    from p3d_cli.render.overlays import equivalent_half_extents

    inertial, computed = link.inertial, computed_inertia(check)
    if inertial is None and computed is None:
        return {"compared with": check.basis} if check.geometry else {}
    declared = declared_inertia(inertial)

    def pair(of_declared, of_computed) -> tuple:
        return (of_declared(inertial) if inertial is not None else "",
                of_computed(computed) if computed is not None else "")

    def box(principal) -> str:
        with np.errstate(all="ignore"):  # moments near float64's limit: shown as inf
            half = None if principal is None else equivalent_half_extents(principal, shape)
            return "" if half is None else _vector(2 * half, 4)

    out: dict[str, object] = {
        "mass (kg)": pair(lambda d: d.mass, lambda c: c.mass),
        "centre of mass (m)": pair(lambda d: _vector(d.center), lambda c: _vector(c.center_of_mass)),
        "ixx iyy izz (kg m^2)": pair(lambda d: _tensor(d.inertia)[0], lambda c: _tensor(c.inertia)[0]),
        "ixy ixz iyz (kg m^2)": pair(lambda d: _tensor(d.inertia)[1], lambda c: _tensor(c.inertia)[1]),
        "principal moments (kg m^2)": pair(lambda d: "" if declared is None else _vector(declared.principal_moments),
                                           lambda c: _vector(c.principal_moments)),
        f"equivalent {shape} (m)": (box(declared), box(computed)),
    }
    if check.moment_ratios is not None:
        out["moment ratios, declared / computed"] = _vector(check.moment_ratios, 4)
    if check.implied_density is not None:
        out["implied density (kg/m^3)"] = check.implied_density
    out["compared with"] = check.basis
    return out


def link_rows(robot, checks, *, shape: str = "box", role: str = "auto", size=PICTURE_SIZE) -> list[Row]:
    """One ``Row`` per link, in the description's order, each with its picture (PNG).

    The copies of a replicated MJCF body share its element, geometry and verdict: they share
    the first copy's picture too (said in their note)."""
    rows = []
    drawn: dict[int, tuple[bytes | None, str, str]] = {}
    for link, check in zip(robot.links, checks):
        first = drawn.get(id(link.node))
        if first is None:
            picture, note = link_picture(robot, link, check, shape=shape, role=role, size=size)
            first = drawn[id(link.node)] = (None if picture is None else picture.to_png(), note, link.name)
        png, note, name = first
        if name != link.name and png is not None:
            note = "; ".join(filter(None, [note, f"drawn as {name}, a copy of the same body"]))
        notes = list(check.notes) + ([note] if note else [])
        rows.append(Row(link.name, check.status, tuple((p.rule, p.message) for p in check.problems), (),
                        link_numbers(link, check, shape), png, "; ".join(notes)))
    return rows


def _intro(robot, shape: str) -> str:
    def swatch(key: str) -> str:
        r, g, b = COLOURS[key]
        return f'<span class="swatch" style="background:#{r:02x}{g:02x}{b:02x}"></span>'

    return (f'<p class="source">{html.escape(robot.path)}</p>'
            f"<p>Each link's geometry in the link frame, with the uniform {shape}{'es' if shape == 'box' else 's'} "
            "of the same mass and "
            f"principal moments as {swatch('declared')}the declared inertial (wide) and {swatch('inertia')}its "
            "geometry at the declared mass (narrow, on top), each on its principal axes at its centre of mass "
            f"(marked; a grey ring circles one too small to see). Inertias that agree give one {shape}; lines "
            "inside the part are drawn half as wide. Failed links first.</p>")


def write_robot_report(robot, checks, html_dir: str | os.PathLike, *, shape: str = "box", role: str = "auto",
                       size=PICTURE_SIZE) -> str:
    """Write the HTML report of ``check_robot(robot, ...)``'s ``checks`` to ``html_dir``
    (``index.html``, pictures in ``images/``); returns the page's path.

    Parameters
    ----------
    shape : {"box", "ellipsoid"}
        The uniform solid drawn for each inertia.
    role : {"auto", "collision", "visual"}
        The geometry drawn for a link whose inertial was compared with none (as ``check_robot``).

    Raises
    ------
    UsageError
        An unknown ``shape``.
    OutputError
        A file cannot be written, or would replace a file the description reads.
    """
    from p3d_cli.render.pages import ordered, write_html
    from p3d_cli.robots.fill import description_files

    if shape not in SHAPES:
        raise UsageError("shape", f"{shape!r} is none of {', '.join(SHAPES)}", "give box or ellipsoid")
    inputs = description_files(robot)
    check_folder(html_dir, inputs)
    rows = ordered(link_rows(robot, checks, shape=shape, role=role, size=size))
    page = write_html(html_dir, COMMAND, rows, inputs=inputs, noun="link", intro=_intro(robot, shape),
                      columns=("declared", "computed"))
    return os.fspath(page)


def check_folder(html_dir: str | os.PathLike, inputs=()) -> None:
    """Refuse, before any work, a report folder that is a file, or whose page would replace one
    of ``inputs`` (a description named ``index.html`` in that folder).

    Raises
    ------
    OutputError
    """
    from p3d_cli.errors import OutputError
    from p3d_cli.io.atomic import same_file

    path = os.fspath(html_dir)
    for target in (path, os.path.join(path, "index.html")):
        for source in inputs:
            if same_file(target, source):
                raise OutputError(path, f"the HTML report would overwrite the input {source}",
                                  "give another folder for the report")
    if os.path.exists(path) and not os.path.isdir(path):
        raise OutputError(path, "the HTML report's folder is a file", "give a folder for the report")
