"""COLLADA (``.dae``): the visual meshes of robot description packages, and many exporters'.

Read by trimesh's loader (it needs pycollada: the ``formats`` extra). Every geometry instance
is placed by its node's whole transform (``<matrix>``, ``<translate>``, ``<rotate>``,
``<scale>`` composed down the node tree). ``<asset><unit meter="..."/>`` is the length unit
(COLLADA 1.4.1 specification, "unit": metres per unit, 1 by default). ``<up_axis>`` is not
applied: coordinates are measured as written, as a URDF's ``<mesh>`` places them. pycollada
parses COLLADA's decimal text as float32 (vertices and transforms alike), so the coordinates
are reported as float32, and the file's decimals are trusted to about 7 digits.
"""

from __future__ import annotations

import math

from p3d_cli.errors import FormatError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import scene_source
from p3d_cli.io.source import MeshSource


def metres_of(units: str | None) -> float:
    """The unit trimesh reports for a DAE (``meters`` or ``0.0254 * meters``) in metres.

    Raises
    ------
    ValueError
        Not of either form, or not positive and finite.
    """
    text = (units or "meters").strip()
    if text == "meters":
        return 1.0
    number, _, rest = text.partition("*")
    if rest.strip() != "meters":
        raise ValueError(text)
    value = float(number)
    if not math.isfinite(value) or value <= 0:
        raise ValueError(text)
    return value


def load(raw: RawInput) -> MeshSource:
    """Read a COLLADA file (see the module's description).

    Raises
    ------
    MissingExtraError
        trimesh or pycollada is not installed.
    FormatError
        Not COLLADA, a unit that is not a positive number of metres, or triangle strips or
        fans (which the loader would leave out).
    InputError
        No triangles.
    """
    from p3d_cli.io.trimesh_scene import load_scene, scene_objects, skipped_note

    data = raw.read_all()
    for tag in (b"<tristrips", b"<trifans"):
        if tag in data:
            # trimesh's loader reads <triangles>, <polylist> and <polygons> only: strips and
            # fans would be left out silently, and with them part of the volume.
            raise FormatError(raw.where, f"it holds {tag.decode()}>, which the COLLADA reader leaves out",
                              "export the model with triangles or polylists")
    scene, log = load_scene(raw, "dae", "COLLADA", ("collada",))
    try:
        metres = metres_of(scene.units)
    except ValueError:
        raise FormatError(raw.where, f"declares unit {scene.units!r}, not a positive number of metres",
                          'write <unit meter="0.001"/> (millimetres) or export it again') from None
    objects, skipped = scene_objects(scene, float32=True)
    return scene_source("dae", raw.where, objects, metres, "geometry instances", skipped_note(skipped, "nodes") + log)
