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
(``p3d_cli.geometry.inertia.combine_mass_properties``). Placement keys are read by the one placement
parser (``p3d_cli.io.placements.placement_from_mapping``), as for scenes and the command line.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from p3d_cli.errors import InputError, P3DError, ReadError, UsageError
from p3d_cli.geometry.placement import IDENTITY, Placement
from p3d_cli.io.placements import placement_from_mapping
from p3d_cli.measure.solid import names_assembly_file

#: Keys of one part.
PART_KEYS = ("name", "mesh", "shape", "assembly", "density", "mass", "translate", "rotate", "quat", "rpy",
             "scale")
#: What a part is made of: exactly one of these.
KINDS = ("mesh", "shape", "assembly")
#: Documented limits (docs/assemblies.md, "Limits"): how deep assembly files may nest, and how
#: many mesh or shape parts an assembly may expand to, counting a file included n times n
#: times. A file naming the previous one twice, 40 levels deep, would otherwise expand to 2⁴⁰
#: parts from a few kilobytes (a "billion laughs").
MAX_NESTING = 64
MAX_PARTS = 100_000


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
    """``thing`` as an assembly: an ``Assembly``, or a path to a file that is one; else None.

    Raises
    ------
    InputError
        A bad file, or an assembly beyond the limits (``expanded_parts``).
    """
    if isinstance(thing, Assembly):
        expanded_parts(thing)
        return thing
    if isinstance(thing, os.PathLike):
        thing = os.fspath(thing)
    if not isinstance(thing, str) or not names_assembly_file(thing):
        return None
    return load_assembly(thing)


def expanded_parts(assembly: Assembly) -> int:
    """How many mesh and shape parts ``assembly`` expands to (a nested assembly included n
    times counts n times), checked against ``MAX_PARTS`` and ``MAX_NESTING``.

    Each distinct nested ``Assembly`` is counted once (memoised), so a file naming the
    previous one twice costs one step per file, not 2ⁿ; the walk's depth is capped by
    ``MAX_NESTING``, so no valid input can exhaust Python's recursion.

    Raises
    ------
    InputError
        Nested more than ``MAX_NESTING`` deep, or more than ``MAX_PARTS`` parts.
    """
    known: dict[int, tuple[int, int]] = {}           # id -> (parts, levels below)

    def walk(a: Assembly, depth: int) -> tuple[int, int]:
        if id(a) not in known:
            if depth >= MAX_NESTING:
                _too_deep(a.source)
            inner = [walk(p.thing, depth + 1) for p in a.parts if isinstance(p.thing, Assembly)]
            leaves = sum(1 for p in a.parts if not isinstance(p.thing, Assembly))
            known[id(a)] = (leaves + sum(n for n, _ in inner), 1 + max((h for _, h in inner), default=0))
        n, height = known[id(a)]
        if depth + height > MAX_NESTING:
            _too_deep(a.source)
        return n, height

    n = walk(assembly, 0)[0]
    if n > MAX_PARTS:
        raise InputError(assembly.source, f"expands to {n:,} parts (nested assemblies included several times "
                         f"count each time), more than p3d's limit of {MAX_PARTS:,}",
                         "include fewer copies, or measure the repeated sub-assembly once and scale its mass")
    return n


def _too_deep(source: str):
    raise InputError(source, f"nests assemblies more than {MAX_NESTING} levels deep",
                     "flatten the nesting (p3d measures at most that depth)")


def load_assembly(path: str, _seen: tuple[str, ...] = (), _loaded: dict | None = None) -> Assembly:
    """Read and check an assembly file (nested files too, each read once however often it is
    included), within ``MAX_NESTING`` and ``MAX_PARTS``.

    Raises
    ------
    InputError
        Not valid YAML, not an assembly, a bad part (``path: parts[i].key: ...``), a cycle, or
        beyond the limits.
    """
    real = os.path.realpath(path)
    if real in _seen:
        raise InputError(path, "includes itself (through nested assemblies)", "remove the cycle")
    top = _loaded is None
    loaded: dict = {} if _loaded is None else _loaded
    if real in loaded:
        # Read before, completely, with no cycle (it could not reach an ancestor of this
        # inclusion without reaching itself): share it.
        return loaded[real]
    if len(_seen) >= MAX_NESTING:
        raise InputError(path, f"is nested more than {MAX_NESTING} assembly files deep",
                         "flatten the nesting (p3d reads at most that depth)")
    assembly = _read_assembly(path, _seen + (real,), loaded)
    loaded[real] = assembly
    if top:
        expanded_parts(assembly)
    return assembly


def _read_assembly(path: str, seen: tuple[str, ...], loaded: dict) -> Assembly:
    from p3d_cli.io.yaml_loader import read_yaml

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
    return parts_assembly(data["parts"], path, f"{path}: parts", os.path.dirname(path), units, seen, loaded)


def parts_assembly(entries: list, source: str, where: str, folder: str, units: str | None = None,
                   _seen: tuple[str, ...] = (), _loaded: dict | None = None) -> Assembly:
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
    loaded: dict = {} if _loaded is None else _loaded
    parts = tuple(_part(entry, f"{where}[{i}]", folder, _seen, loaded) for i, entry in enumerate(entries))
    assembly = Assembly(source, parts, units)
    if _loaded is None:
        expanded_parts(assembly)
    return assembly


def _part(entry, where: str, folder: str, seen: tuple[str, ...], loaded: dict) -> Part:
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
            raise ReadError(f"{where}.{kind}", f"no such file {path}", "paths are relative to the assembly file")
        thing = load_assembly(path, seen, loaded) if kind == "assembly" else path
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
