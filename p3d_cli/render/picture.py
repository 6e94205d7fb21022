"""``picture``: a shaded picture of a mesh, shape or assembly, with overlays; and the ``Picture`` value.

The road: resolve the thing into triangles (``geometry``), measure what the overlays need
(``p3d.props`` for the principal frame, ``defects`` for the problem edges), choose the camera
and fit the frame, z-buffer the faces (``raster``), shade them (``shade``), draw the overlays
against the depth buffer (``draw``), add the title and the legend (``legend``).
"""

from __future__ import annotations

from typing import Any, Iterable

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.render.camera import VIEWS, make_camera
from p3d_cli.render.image import Picture
from p3d_cli.render.overlays import SHOW, Layer

#: Largest picture side, in pixels (a 16k x 16k picture is 768 MB of RGB).
MAX_SIDE = 8192


def parse_show(show: Iterable[str] | str | None) -> tuple[str, ...]:
    """``show`` as overlay names (a comma-separated string or names; ``all``, ``none``).

    Raises
    ------
    UsageError
    """
    if show is None:
        return ()
    items = [show] if isinstance(show, str) else list(show)
    names: list[str] = []
    for item in items:
        for name in (part.strip().lower() for part in str(item).split(",")):
            if name in ("", "none"):
                continue
            if name == "all":
                names += [n for n in SHOW if n != "ellipsoid"]
            elif name in SHOW:
                names.append(name)
            else:
                raise UsageError("show", f"nothing named {name!r} to show", "choose from " + ", ".join(SHOW)
                                 + " (or all)")
    return tuple(n for n in SHOW if n in names)


def check_size(size) -> tuple[int, int]:
    """``(width, height)`` as whole pixels within the limits.

    Raises
    ------
    UsageError
    """
    try:
        width, height = (int(v) for v in size)
    except (TypeError, ValueError):
        raise UsageError("size", f"{size!r} is not a width and a height", "give two whole numbers, e.g. 800, 600") \
            from None
    if not (64 <= width <= MAX_SIDE and 64 <= height <= MAX_SIDE):
        raise UsageError("size", f"{width}x{height} is outside 64..{MAX_SIDE} pixels a side",
                         "choose a size such as 800x600")
    return width, height


def picture(thing: Any, *, view: str | None = "iso", azimuth: float | None = None, elevation: float | None = None,
           up: str = "z", size=(800, 600), show: Iterable[str] | str | None = (), format: str | None = None,
           placement=None, title: str | None = None, segments: int | None = None) -> Picture:
    """A shaded picture of a mesh, shape or assembly, with overlays and a legend.

    Parameters
    ----------
    thing : path, spec, shape, triangles, (vertices, faces), MeshSource or Assembly
        Anything ``p3d.props`` takes.
    view : {"iso", "front", "back", "left", "right", "top", "bottom"}
        A standard view (docs/render.md); ``azimuth`` and ``elevation`` (degrees) override it.
    up : {"z", "y", "x"}
        The part's up axis (meshes from scanners and games are often y-up).
    size : (int, int)
        Width and height of the whole picture in pixels (title and legend included).
    show : iterable of str or str
        Overlays (``p3d_cli.render.overlays.SHOW``): ``defects``, ``axes``, ``inertia``,
        ``ellipsoid``, ``bounds``; ``all`` for all but the ellipsoid.
    format : str, optional
        Format name for a path.
    placement : Placement, optional
        Scale, rotate and move the thing first (as for ``p3d.props``).
    title : str, optional
        Instead of the input's name.
    segments : int, optional
        Segments of a round shape's polyhedron (default 64).

    Returns
    -------
    Picture

    Raises
    ------
    P3DError
        ``UsageError`` for bad parameters; as ``p3d.props`` for an input it cannot read.
    """
    from p3d_cli.render.compose import compose
    from p3d_cli.render.geometry import ROUND_SEGMENTS, scene_triangles

    width, height = check_size(size)
    names = parse_show(show)
    camera = make_camera(view, azimuth, elevation, up)
    scene = scene_triangles(thing, format=format, placement=placement, segments=segments or ROUND_SEGMENTS)
    layers = overlay_layers(scene, names)
    shown = view if azimuth is None and elevation is None and view in VIEWS else None
    note = f"{shown} view" if shown else f"azimuth {camera.azimuth:g}, elevation {camera.elevation:g}"
    name = title if title is not None else scene.source
    count = f"{len(scene.triangles):,} triangles" + (f", {scene.parts} parts" if scene.kind == "assembly" else "")
    return compose(scene.triangles, camera, (width, height), layers, f"{name}  ({count})", note)


def overlay_layers(scene, names: tuple[str, ...]) -> list[Layer]:
    """The layers of the overlays ``names`` for ``scene`` (a ``SceneGeometry``)."""
    from p3d_cli.render import overlays

    layers: list[Layer] = []
    if not names:
        return layers
    triangles = scene.triangles
    if "defects" in names:
        if scene.kind != "mesh":
            raise UsageError("show", f"defects: {scene.source} is a {scene.kind}, not a mesh",
                             "show defects of mesh files (shapes are clean by construction)")
        from p3d_cli.render.defects import defect_geometry

        intersecting, count = self_intersections(scene)
        layers += overlays.defect_layers(defect_geometry(triangles), intersecting, count)
    if {"axes", "inertia", "ellipsoid", "bounds"} & set(names):
        from p3d_cli.measure import props

        result = props(scene.measure, **scene.options)
        bounds = result.facts.bounds
        if "axes" in names and bounds is not None:
            layers += overlays.axis_layers(result.properties, float(bounds.size.max()))
        for shape in ("inertia", "ellipsoid"):
            if shape in names:
                layer = overlays.inertia_layer(result.properties, "box" if shape == "inertia" else "ellipsoid")
                if layer is not None:
                    layers.append(layer)
        if "bounds" in names and bounds is not None:
            layers.append(overlays.bounds_layer(bounds))
    return layers


def self_intersections(scene) -> tuple[np.ndarray | None, int | None]:
    """The faces ``p3d check`` reports as crossing others, and how many crossings it counts;
    ``(None, None)`` when this p3d's check does not look for them.

    ``p3d check`` gains the self-intersection test in its own change (issue 29); its report's
    ``self_intersection_samples`` (each with the ``faces`` of a crossing pair) and its count
    ``self_intersections`` are read by name, so that this overlay works with or without it.
    """
    from p3d_cli.measure import check
    from p3d_cli.mesh.report import TopologyReport

    if "self_intersection_samples" not in getattr(TopologyReport, "__dataclass_fields__", {}):
        return None, None          # this check does not look for them: do not run it for nothing
    report = check(scene.measure).report
    samples = getattr(report, "self_intersection_samples", None)
    if samples is None:
        return None, None
    faces = sorted({int(f) for sample in samples for f in getattr(sample, "faces", ())})
    return np.array(faces, dtype=np.int64), getattr(report, "self_intersections", len(samples))
