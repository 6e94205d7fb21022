"""The triangles a picture shows: a mesh as read, a shape's polyhedron, an assembly's parts placed.

One function, ``scene_triangles``, takes whatever ``p3d.props`` takes and returns one triangle
array in one frame, with what the overlays need to be measured on the same thing (the
measurement's own input and its options, so that the principal frame drawn is the one
``p3d props`` reports for it).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from p3d_cli.geometry.placement import IDENTITY, Placement

#: Segments of a round shape's polyhedron in a picture (a sphere: 64 around, 32 stacks).
ROUND_SEGMENTS = 64


@dataclass(frozen=True)
class SceneGeometry:
    """What a picture shows.

    Attributes
    ----------
    triangles : (n, 3, 3) float32 or float64
        Corners in the frame of the measurement (an assembly's parts placed, in its own unit).
    source : str
        The input's name for the title.
    kind : str
        ``mesh``, ``shape`` or ``assembly``.
    measure : object
        What to hand ``p3d.props`` / ``p3d.check`` for the overlays (a loaded mesh, a shape, an
        assembly), and ``options``: the keyword arguments that go with it.
    parts : int
        Number of parts (1 but for an assembly).
    """

    triangles: np.ndarray
    source: str
    kind: str
    measure: Any
    options: dict = field(default_factory=dict)
    parts: int = 1


def scene_triangles(thing: Any, *, format: str | None = None, placement: Placement | None = None,
                    segments: int = ROUND_SEGMENTS) -> SceneGeometry:
    """The triangles of ``thing`` (anything ``p3d.props`` takes), placed.

    Raises
    ------
    P3DError
        As ``p3d.props`` for an input it cannot read.
    """
    from p3d_cli.errors import UsageError
    from p3d_cli.measure import as_solid, find_assembly

    placement = IDENTITY if placement is None else placement
    found = find_assembly(thing) if isinstance(thing, (str, os.PathLike)) or type(thing).__name__ == "Assembly" \
        else None
    if found is not None:
        return _assembly(found, placement, segments)
    solid = as_solid(thing, format=format)
    if solid.shape is not None:
        shape = placement.shape(solid.shape)
        triangles = shape.triangles() if shape.polyhedral else shape.tessellate(segments)
        triangles = _place(triangles, Placement(None, placement.rotation, placement.translation))
        return SceneGeometry(triangles, solid.source, "shape", solid.shape, {"placement": placement})
    mesh = solid.mesh
    if mesh.tetrahedra is not None:
        raise UsageError("thing", f"{solid.where} is a volume (tetrahedral) mesh",
                         "export its boundary surface to draw it")
    triangles = _place(np.asarray(mesh.triangles()), placement)
    _refuse_nonfinite(triangles, solid.where)
    return SceneGeometry(triangles, solid.source, "mesh", mesh, {"placement": placement})


def _assembly(assembly, placement: Placement, segments: int) -> SceneGeometry:
    """Every part placed, in the assembly's own length unit (its numbers read as written)."""
    from p3d_cli.measure import placed_parts

    units = assembly.units
    pieces = []
    count = 0
    for solid, total in placed_parts(assembly, placement, units):
        if solid.shape is not None:
            shape = total.shape(solid.shape)
            triangles = shape.triangles() if shape.polyhedral else shape.tessellate(segments)
            pieces.append(_place(triangles, Placement(None, total.rotation, total.translation)))
        else:
            pieces.append(_place(np.asarray(solid.mesh.triangles(), dtype=np.float64), total))
            _refuse_nonfinite(pieces[-1], solid.where)
        count += 1
    triangles = np.concatenate(pieces) if pieces else np.zeros((0, 3, 3))
    options: dict[str, Any] = {"placement": placement}
    if units is not None:
        options["output_units"] = f"{units},kg"
    return SceneGeometry(triangles, assembly.source, "assembly", assembly, options, count)


def _place(triangles: np.ndarray, placement: Placement) -> np.ndarray:
    """Triangles after ``placement`` (a mirror also swaps two corners, keeping the winding
    outward, as ``p3d_cli.geometry.placement`` does for the measurement)."""
    if placement.is_identity:
        return triangles
    shape = triangles.shape
    out = placement.points(triangles.reshape(-1, 3)).reshape(shape)
    if placement.scale is not None and np.prod(np.sign(placement.scale)) < 0:
        out = out[:, [0, 2, 1]]
    return out


def _refuse_nonfinite(triangles: np.ndarray, where: str) -> None:
    from p3d_cli.io.source import first_nonfinite, nonfinite_error

    bad = first_nonfinite(triangles)
    if bad is not None:
        raise nonfinite_error(where, bad)
