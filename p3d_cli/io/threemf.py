"""3MF (3D Manufacturing Format): the zip package slicers and CAD write today.

Read by trimesh's loader (it needs lxml and networkx: the ``formats`` extra). Every build item
is placed by its transform, through the components it refers to. The model's ``unit``
attribute (3MF core specification §3.4: micron, millimeter, centimeter, inch, foot, meter;
millimetre by default) is the length unit of its coordinates. Vertices are decimal text, read
as float64.
"""

from __future__ import annotations

from p3d_cli.errors import FormatError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import scene_source
from p3d_cli.io.source import MeshSource

#: The ``unit`` values of the 3MF core specification, in metres.
UNITS = {"micron": 1e-6, "millimeter": 1e-3, "centimeter": 1e-2, "inch": 0.0254, "foot": 0.3048, "meter": 1.0}


def load(raw: RawInput) -> MeshSource:
    """Read a 3MF package (see the module's description).

    Raises
    ------
    MissingExtraError
        trimesh, lxml or networkx is not installed.
    FormatError
        Not a 3MF package, or a unit the specification does not define.
    InputError
        No triangles.
    """
    from p3d_cli.io.trimesh_scene import load_scene, scene_objects, skipped_note

    if raw.head(2) != b"PK":
        raise FormatError(raw.where, "is not a 3MF package (not a zip archive)", "export it again as 3MF")
    scene, log = load_scene(raw, "3mf", "3MF", ("lxml", "networkx"))
    unit = str(scene.units or "millimeter").lower()
    if unit not in UNITS:
        raise FormatError(raw.where, f"declares unit {unit!r}, which 3MF does not define",
                          "use one of " + ", ".join(UNITS))
    objects, skipped = scene_objects(scene)
    return scene_source("3mf", raw.where, objects, UNITS[unit], "objects (build items and their components)",
                        skipped_note(skipped, "items") + log)
