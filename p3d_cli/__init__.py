"""p3d: exact mass properties, bounds and constraint solves for meshes and shapes.

The command line (``p3d props``, ``p3d bounds``, ``p3d check``, ``p3d repair``, ``p3d solve``) calls
exactly these functions::

    import p3d_cli as p3d

    result = p3d.props("part.stl", density=7850)          # a path, spec, shape, array or (V, F)
    result.properties.mass, result.properties.inertia
    p3d.bounds("box:1,2,3", p3d.Placement(rotation=p3d.rotation_from_axis_degrees("z", 30)))
    p3d.check("part.stl").ok
    mesh, report = p3d.repair("part.stl")                # fixed, with every change said

Names are imported on first use (as scikit-image's ``lazy.attach`` does), so ``import p3d_cli``
costs almost nothing and ``p3d props tiny.stl`` starts as fast as before. See docs/api.md.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name -> the module that defines it.
_API = {
    # measuring
    "props": "p3d_cli.measure",
    "bounds": "p3d_cli.measure",
    "check": "p3d_cli.measure",
    "self_intersections": "p3d_cli.measure",
    # inputs
    "load_mesh": "p3d_cli.io",
    "parse_shape": "p3d_cli.shapes",
    "as_solid": "p3d_cli.measure.solid",
    "Solid": "p3d_cli.measure.solid",
    "MeshSource": "p3d_cli.io.source",
    "FORMATS": "p3d_cli.io.formats",
    "SHAPES": "p3d_cli.shapes",
    # and every shape class by its own name (``p3d.Box``): ``_shape_classes``, from ``SHAPES``
    # pictures
    "picture": "p3d_cli.render.picture",
    "Picture": "p3d_cli.render.image",
    # placing
    "Placement": "p3d_cli.geometry.placement",
    "rotation_from_axis_degrees": "p3d_cli.geometry.rotation",
    "rotation_from_quaternion": "p3d_cli.geometry.rotation",
    "quaternion_matrix": "p3d_cli.geometry.rotation",
    "compose_rotations": "p3d_cli.geometry.rotation",
    # from moments to mass properties
    "mass_properties": "p3d_cli.geometry.inertia",
    # results
    "PropsResult": "p3d_cli.results",
    "BoundsResult": "p3d_cli.results",
    "MassProperties": "p3d_cli.results",
    "MeshFacts": "p3d_cli.results",
    "Moments": "p3d_cli.results",
    "Bounds": "p3d_cli.results",
    "CheckResult": "p3d_cli.mesh.verdicts",
    "SelfIntersections": "p3d_cli.mesh.solidity_report",
    # repairing
    "repair": "p3d_cli.repairs",
    "repair_file": "p3d_cli.repairs",
    "RepairReport": "p3d_cli.repairs",
    "RepairedMesh": "p3d_cli.repairs",
    # robot descriptions (URDF, MJCF, SDF)
    "load_robot": "p3d_cli.robots",
    "check_robot": "p3d_cli.robots",
    "fill_robot": "p3d_cli.robots",
    # assemblies
    "load_assembly": "p3d_cli.measure.assembly.parts",
    # constraint scenes
    "load_scene": "p3d_cli.constraints",
    "parse_scene": "p3d_cli.constraints",
    "solve_scene": "p3d_cli.constraints",
    "SolveResult": "p3d_cli.constraints",
    # errors
    "P3DError": "p3d_cli.errors",
    "InputError": "p3d_cli.errors",
    "ReadError": "p3d_cli.errors",
    "FormatError": "p3d_cli.errors",
    "UnknownFormatError": "p3d_cli.errors",
    "UsageError": "p3d_cli.errors",
    "SpecError": "p3d_cli.errors",
    "SceneError": "p3d_cli.errors",
    "MissingExtraError": "p3d_cli.errors",
    "CheckFailedError": "p3d_cli.errors",
}



def _shape_classes() -> dict[str, Any]:
    """Class name -> shape class, for every class in ``SHAPES`` (which the classes build)."""
    return importlib.import_module("p3d_cli.shapes").public_classes()


def __getattr__(name: str) -> Any:
    if name == "__all__":     # every public name; the shapes' are known once they are imported
        return ["__version__", *_API, *_shape_classes()]
    module = _API.get(name)
    if module is None:
        shapes = _shape_classes()
        if name in shapes:
            return shapes[name]   # not kept: SHAPES stays the one record of which shapes there are
        raise AttributeError(f"module 'p3d_cli' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # the next look-up is a plain attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_API) | set(_shape_classes()))


if TYPE_CHECKING:  # what type checkers and editors see; nothing is imported at run time
    from p3d_cli.constraints import SolveResult, load_scene, parse_scene, solve_scene
    from p3d_cli.errors import (
        CheckFailedError,
        FormatError,
        InputError,
        MissingExtraError,
        P3DError,
        ReadError,
        SceneError,
        SpecError,
        UnknownFormatError,
        UsageError,
    )
    from p3d_cli.geometry.inertia import mass_properties
    from p3d_cli.geometry.placement import Placement
    from p3d_cli.geometry.rotation import (
        compose_rotations,
        quaternion_matrix,
        rotation_from_axis_degrees,
        rotation_from_quaternion,
    )
    from p3d_cli.io import load_mesh
    from p3d_cli.io.formats import FORMATS
    from p3d_cli.io.source import MeshSource
    from p3d_cli.measure import bounds, check, props, self_intersections
    from p3d_cli.measure.solid import Solid, as_solid
    from p3d_cli.mesh.solidity_report import SelfIntersections
    from p3d_cli.mesh.verdicts import CheckResult
    from p3d_cli.render.image import Picture
    from p3d_cli.render.picture import picture
    from p3d_cli.repairs import RepairedMesh, RepairReport, repair, repair_file
    from p3d_cli.results import Bounds, BoundsResult, MassProperties, MeshFacts, Moments, PropsResult
    from p3d_cli.shapes import SHAPES, parse_shape
    from p3d_cli.shapes.classes import *  # noqa: F403 - every shape class, by its own name
