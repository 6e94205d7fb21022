"""Assemblies: several parts, each placed and of its own material, measured as one whole.

An assembly file is YAML recognised by its content (a top-level ``parts:`` list)::

    units: mm                       # optional: the length unit of meshes and translations
    parts:
      - name: base
        mesh: base.stl              # relative to this file
        density: 7.85 g/cm^3
      - name: arm
        shape: box:10,20,30
        mass: 0.5 kg
        translate: [0, 0, 100]
        rotate: {axis: z, degrees: 30}   # or quat: [w, x, y, z], or rpy: [r, p, y] (radians)
        scale: [1, -1, 1]                # negative: mirrored
      - name: bracket
        assembly: bracket.yaml           # nested

Each part is measured exactly as a single input is (``p3d_cli.measure``), placed in the
assembly's frame, and the parts are summed: masses and volumes add, the centre of mass is
the mass-weighted mean, and second moments about it add with the parallel-axis terms
(``p3d_cli.inertia.combine_mass_properties``). Placement keys are read by the one placement
parser (``p3d_cli.placement_text.placement_from_mapping``), as for scenes and the command line.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from p3d_cli.errors import InputError, P3DError, UsageError
from p3d_cli.placement import IDENTITY, Placement
from p3d_cli.placement_text import placement_from_mapping
from p3d_cli.solid import names_assembly_file

#: Keys of one part.
PART_KEYS = ("name", "mesh", "shape", "assembly", "density", "mass", "translate", "rotate", "quat", "rpy",
             "scale")
#: What a part is made of: exactly one of these.
KINDS = ("mesh", "shape", "assembly")


@dataclass(frozen=True)
class Part:
    """One part: what it is, where it goes, what it is made of.

    Attributes
    ----------
    name : str
    thing : str or Assembly
        A mesh path (already joined to the assembly file's folder), a shape spec, an ``Assembly``.
    placement : Placement
        In the assembly's length unit.
    density, mass : float or str or None
        Bare numbers or text with a unit; at most one.
    where : str
        ``assembly.yaml: parts[1]``, for messages.
    """

    name: str
    thing: Any
    placement: Placement = IDENTITY
    density: float | str | None = None
    mass: float | str | None = None
    where: str = ""


@dataclass(frozen=True)
class Assembly:
    """Parts in one frame. ``units``: the length unit of its meshes and translations."""

    source: str
    parts: tuple[Part, ...] = field(default_factory=tuple)
    units: str | None = None


def combine(inputs, source: str = "<combined>") -> Assembly:
    """An assembly of the inputs as they are (``p3d props a.stl b.stl --combine``)."""
    return Assembly(source, tuple(Part(str(x), x, where=f"{source}: {x}") for x in inputs))


def find_assembly(thing) -> Assembly | None:
    """``thing`` as an assembly: an ``Assembly``, or a path to a file that is one; else None."""
    if isinstance(thing, Assembly):
        return thing
    if isinstance(thing, os.PathLike):
        thing = os.fspath(thing)
    if not isinstance(thing, str) or not names_assembly_file(thing):
        return None
    return load_assembly(thing)


def load_assembly(path: str, _seen: tuple[str, ...] = ()) -> Assembly:
    """Read and check an assembly file (nested files too).

    Raises
    ------
    InputError
        Not valid YAML, not an assembly, a bad part (``path: parts[i].key: ...``), a cycle.
    """
    from p3d_cli.constraints.yaml_loader import read_yaml

    real = os.path.realpath(path)
    if real in _seen:
        raise InputError(path, "includes itself (through nested assemblies)", "remove the cycle")
    data = read_yaml(path, path, InputError)  # the scenes' hardened reader: duplicate keys, size, depth
    if not isinstance(data, dict) or not isinstance(data.get("parts"), list) or not data["parts"]:
        raise InputError(path, "is not an assembly (no list of parts)", "write parts: with one entry per part")
    unknown = [k for k in data if k not in ("units", "parts", "name")]
    if unknown:
        raise InputError(f"{path}: {unknown[0]}", "unknown key", "an assembly has units: and parts:")
    units = data.get("units")
    if units is not None:
        from p3d_cli.units import check_length

        try:
            check_length(str(units))
        except UsageError as exc:
            raise InputError(f"{path}: units", exc.what, exc.hint) from None
        units = str(units)
    return parts_assembly(data["parts"], path, f"{path}: parts", os.path.dirname(path), units, _seen + (real,))


def parts_assembly(entries: list, source: str, where: str, folder: str, units: str | None = None,
                   _seen: tuple[str, ...] = ()) -> Assembly:
    """The assembly of a YAML list of parts (an assembly file's ``parts:``, a scene body's).

    Parameters
    ----------
    entries : list
        One mapping per part (``mesh:``/``shape:``/``assembly:``, placement, density or mass).
    source : str
        What the assembly is called in results (a file's path, ``scene.yaml: bodies.arm``).
    where : str
        The list's place for messages (``scene.yaml: bodies.arm.parts``).
    folder : str
        Mesh and assembly paths are relative to it.
    units : str, optional

    Raises
    ------
    InputError
        An empty list, or a bad part (``<where>[i].key: ...``).
    """
    if not isinstance(entries, list) or not entries:
        raise InputError(where, "is not a list of parts", "write one entry per part: - shape: box:1,1,1")
    parts = tuple(_part(entry, f"{where}[{i}]", folder, _seen) for i, entry in enumerate(entries))
    return Assembly(source, parts, units)


def _part(entry, where: str, folder: str, seen: tuple[str, ...]) -> Part:
    if not isinstance(entry, dict):
        raise InputError(where, "is not a mapping", "write each part as keys: name, mesh or shape, placement")
    for key in entry:
        if key not in PART_KEYS:
            raise InputError(f"{where}.{key}", "unknown key", "part keys are: " + ", ".join(PART_KEYS))
    kinds = [k for k in KINDS if k in entry]
    if len(kinds) != 1:
        raise InputError(where, "needs exactly one of mesh:, shape:, assembly:" + (f" (has {', '.join(kinds)})"
                                                                                  if kinds else ""),
                         "say what the part is")
    kind = kinds[0]
    value = entry[kind]
    if not isinstance(value, str) or not value.strip():
        raise InputError(f"{where}.{kind}", "is not text", "write a path (relative to this file) or a spec")
    thing: Any = value
    if kind == "shape":
        from p3d_cli.shapes import parse_shape

        try:
            parse_shape(value)
        except P3DError as exc:
            raise InputError(f"{where}.shape", exc.what, exc.hint) from None
    else:
        path = value if os.path.isabs(value) else os.path.join(folder, value)
        if not os.path.isfile(path):
            raise InputError(f"{where}.{kind}", f"no such file {path}", "paths are relative to the assembly file")
        thing = load_assembly(path, seen) if kind == "assembly" else path
    name = entry.get("name", os.path.basename(value) if kind != "shape" else value)
    if not isinstance(name, (str, int)) or isinstance(name, bool):
        raise InputError(f"{where}.name", "is not text", "write a name such as base")
    amounts = {}
    for key in ("density", "mass"):
        if key in entry:
            v = entry[key]
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                raise InputError(f"{where}.{key}", "is not a number or a quantity", "write e.g. 7850 kg/m^3")
            amounts[key] = v if isinstance(v, str) else float(v)
    if len(amounts) == 2:
        raise InputError(f"{where}.mass", "given with density:", "give one: the other follows from the volume")
    placement = placement_from_mapping(entry, where)
    return Part(str(name), thing, placement, amounts.get("density"), amounts.get("mass"), where)
