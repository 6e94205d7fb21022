"""``p3d check`` of an assembly file: each mesh part checked on its own, one verdict for the whole.

An assembly (``p3d_cli.measure.assembly.parts``) is measured by ``props`` and ``bounds`` part by part; ``check``
reads it the same way. Every mesh part (nested assemblies' too) is checked in its own file's
frame, as ``p3d check part.stl`` would check it: placement does not change topology, and a
mirrored part (negative scale) is measured with its winding flipped, so its own file must be
outward. Shape parts are clean solids by construction and are passed over. The whole's counts
are the parts' sums; it fails where any part fails (``NAME:CHECK``), and the limits
(``min_volume``, ``max_faces``) apply to each part and to the sums.
"""

from __future__ import annotations

import dataclasses
from typing import Callable, Iterable, Iterator

from p3d_cli.errors import InputError, P3DError
from p3d_cli.measure.assembly.parts import Assembly


def mesh_parts(assembly: Assembly, path: str = "") -> Iterator[tuple[str, str, str]]:
    """``(name path, mesh path, where)`` of every mesh part, nested assemblies included."""
    from p3d_cli.shapes import parse_spec

    for part in assembly.parts:
        name = f"{path}{part.name}"
        if isinstance(part.thing, Assembly):
            yield from mesh_parts(part.thing, name + "/")
        elif isinstance(part.thing, str) and parse_spec(part.thing) is None:
            yield name, part.thing, part.where


def check_assembly(assembly: Assembly, check: Callable, required: Iterable[str], min_volume: float | None = None,
                   max_faces: int | None = None):
    """The ``CheckResult`` of an assembly: its mesh parts' verdicts as ``parts``, each made by
    ``check(path, require=, min_volume=, max_faces=)`` (``p3d_cli.measure.check``).

    Raises
    ------
    InputError
        A part's mesh cannot be read (named by the part: ``link.yaml: parts[1]``), or the
        assembly has no mesh part at all.
    """
    from p3d_cli.mesh.report import TopologyReport
    from p3d_cli.mesh.verdicts import CheckResult

    required = tuple(required)
    parts = []
    for name, mesh, where in mesh_parts(assembly):
        try:
            parts.append((name, check(mesh, require=required, min_volume=min_volume, max_faces=max_faces)))
        except P3DError as exc:
            raise InputError(f"{where}: {exc.where}", exc.what, exc.hint) from None
    if not parts:
        raise InputError(assembly.source, "has no mesh part (shapes are clean solids by construction)",
                         "check an assembly that holds mesh files")
    sums = {f.name: sum(getattr(p.report, f.name) for _, p in parts)
            for f in dataclasses.fields(TopologyReport) if f.type in ("int", int)}
    shells = tuple(s for _, p in parts for s in p.report.shell_list)
    report = TopologyReport(**sums, shell_list=shells[:10], volume=sum(p.report.volume for _, p in parts))
    failed = [f"{name}:{c}" for name, p in parts for c in p.failed]
    if min_volume is not None and not report.volume >= min_volume:
        failed.insert(0, "min-volume")
    if max_faces is not None and report.faces > max_faces:
        failed.insert(0, "max-faces")
    return CheckResult(assembly.source, "assembly", report, required, tuple(dict.fromkeys(failed)), tuple(parts))


__all__ = ["check_assembly", "mesh_parts"]
