"""The one road from a thing to a result: ``props``, ``bounds`` and ``check``.

A thing (a path, ``-``, a shape spec or object, a triangle array, a ``(vertices, faces)``
pair, a loaded mesh, an assembly) is resolved once, into a ``Solid`` (``solid``) or an
``Assembly`` (``assembly``); a solid is then measured exactly (``exact``: closed forms, the
divergence theorem) or by sampling (``montecarlo``), and an assembly part by part, then as a
whole. Everything outside this folder calls the names below, never the modules behind them:
the three measurements, the input resolved (``as_solid``, ``solid_moments``), and assemblies
(their values, their files, and their parts placed, for those that draw them).

Names are imported on first use, so that ``p3d props part.stl`` reads no assembly or Monte
Carlo module it does not need.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

#: Public name -> the module of this folder that defines it.
_FACE = {
    "props": "p3d_cli.measure.measurements",
    "bounds": "p3d_cli.measure.measurements",
    "check": "p3d_cli.measure.measurements",
    "self_intersections": "p3d_cli.measure.measurements",
    "check_props_options": "p3d_cli.measure.measurements",
    "METHODS": "p3d_cli.measure.measurements",
    "Solid": "p3d_cli.measure.solid",
    "as_solid": "p3d_cli.measure.solid",
    "names_assembly_file": "p3d_cli.measure.solid",
    "solid_moments": "p3d_cli.measure.exact",
    "Assembly": "p3d_cli.measure.assembly.parts",
    "Part": "p3d_cli.measure.assembly.parts",
    "combine": "p3d_cli.measure.assembly.parts",
    "find_assembly": "p3d_cli.measure.assembly.parts",
    "load_assembly": "p3d_cli.measure.assembly.parts",
    "parts_assembly": "p3d_cli.measure.assembly.parts",
    "placed_parts": "p3d_cli.measure.assembly.whole",
    "at_mass": "p3d_cli.measure.assembly.whole",
}

__all__ = list(_FACE)


def __getattr__(name: str) -> Any:
    module = _FACE.get(name)
    if module is None:
        raise AttributeError(f"module 'p3d_cli.measure' has no attribute {name!r}")
    return getattr(importlib.import_module(module), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_FACE))


if TYPE_CHECKING:  # what type checkers and readers see; nothing is imported at run time
    from p3d_cli.measure.assembly.parts import Assembly, Part, combine, find_assembly, load_assembly, parts_assembly
    from p3d_cli.measure.assembly.whole import at_mass, placed_parts
    from p3d_cli.measure.exact import solid_moments
    from p3d_cli.measure.measurements import METHODS, bounds, check, check_props_options, props, self_intersections
    from p3d_cli.measure.solid import Solid, as_solid, names_assembly_file
