"""The library's repair calls: ``repair`` (a thing in, a mesh and a report out) and
``repair_file`` (a file in, a file out: what ``p3d repair`` runs for each input)."""

from __future__ import annotations

import dataclasses
import os
import shutil
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, BinaryIO, Iterable

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.io.source import MeshSource, array_source
from p3d_cli.repairs.draft import Draft
from p3d_cli.repairs.fill import FLATNESS, MAX_EDGES
from p3d_cli.repairs.pipeline import repair_triangles
from p3d_cli.repairs.report import MassChange, RepairReport
from p3d_cli.mesh.weld import check_tolerance
from p3d_cli.repairs.steps import resolve_steps


@dataclass(frozen=True)
class RepairedMesh:
    """A repaired mesh: its triangles as written to STL, and as vertices and faces.

    Attributes
    ----------
    triangles : (n, 3, 3) float32 or float64
        In the input's dtype; each input face the repair did not move exactly as the input
        stored it (a flipped face with its corners 1 and 2 swapped).
    coordinate_dtype : str
        ``float32`` or ``float64``, the input's.
    """

    triangles: np.ndarray
    coordinate_dtype: str
    draft: Draft | None = field(default=None, repr=False, compare=False)

    @cached_property
    def _indexed(self) -> tuple[np.ndarray, np.ndarray]:
        draft = self.draft
        if draft is None:       # nothing was repaired: index the input's corners as check does
            from p3d_cli.mesh.topology import corner_vertex_ids

            ids, _ = corner_vertex_ids(self.triangles)
            points = np.empty((int(ids.max()) + 1 if ids.size else 0, 3), dtype=self.triangles.dtype)
            points[ids.ravel()] = self.triangles.reshape(-1, 3)
            draft = Draft.of(self.triangles, ids, points)
        return draft.indexed()

    @property
    def vertices(self) -> np.ndarray:
        """``(m, 3)``: each vertex once, numbered in order of first use, in the input's dtype."""
        return self._indexed[0]

    @property
    def faces(self) -> np.ndarray:
        """``(n, 3)`` int64: 0-based vertex indices of every face, in output order."""
        return self._indexed[1]

    @property
    def source(self) -> MeshSource:
        """The mesh as a ``MeshSource``: ``p3d.props(mesh.source)``, ``p3d.check(mesh.source)``."""
        return array_source("repaired", self.triangles, self.coordinate_dtype)


def repair(thing: Any, steps: Iterable[str] | str | None = None, weld: float | None = None, *,
           fill_holes: str = "flat", flatness: float = FLATNESS, max_hole_edges: int = MAX_EDGES,
           require: Iterable[str] | None = None, format: str | None = None,
           stdin: BinaryIO | None = None) -> tuple[RepairedMesh, RepairReport]:
    """Fix what ``p3d check`` finds in a mesh, change nothing else, and say every change.

    A mesh that ``check`` passes comes back unchanged. Otherwise the steps run in their order
    (``p3d_cli.repairs.steps.STEPS``): ``weld`` (only with a tolerance), ``degenerate``,
    ``duplicate``, ``orient``, ``holes``, ``outward``. What they cannot fix (non-manifold edges
    and vertices, holes that are not simple and flat, self-intersections) is left and said.

    Parameters
    ----------
    thing : str, os.PathLike, array_like, (vertices, faces) or MeshSource
        The mesh (``p3d_cli.measure.as_solid``); a file of several objects is repaired as one mesh.
    steps : iterable of str or str, optional
        The steps to run (default: all but ``weld``, which runs with a tolerance); ``-name``
        leaves one out (``"-holes"``).
    weld : float, optional
        Merge vertices closer than this (in the mesh's units) first; vertices are otherwise
        matched by exact coordinates.
    fill_holes : {"flat", "any"}
        ``flat`` fills loops whose corners lie within ``flatness`` of their plane (as a fraction
        of the loop's size) and that have at most ``max_hole_edges`` edges; ``any`` fills every
        loop that is simple seen along its normal.
    flatness, max_hole_edges
        The limits of ``flat``.
    require : iterable of str, optional
        The checks of ``p3d check`` that decide whether the mesh needs repair and whether the
        output is fixed (``p3d_cli.mesh.verdicts.CHECKS``; default all). Leaving out
        ``no-self-intersection`` and ``nesting`` skips the exact self-intersection test.
    format, stdin
        As for ``p3d_cli.measure.props``.

    Returns
    -------
    mesh : RepairedMesh
    report : RepairReport
        ``fixed`` (the output passes ``check``), each step's counts and locations, the mass
        properties before and after (``report.mass``), and ``unfixed``: what is left and why.

    Raises
    ------
    UsageError
        Bad steps, tolerance or policy; a shape spec (shapes are solids by construction).
    InputError
        An unreadable input, a volume mesh, a mesh without faces or with a NaN coordinate.

    Examples
    --------
    >>> import numpy as np
    >>> import p3d_cli as p3d
    >>> cube = p3d.Box(0.5, 0.5, 0.5).triangles()
    >>> mesh, report = p3d.repair(cube[1:])           # a cube with a triangle missing
    >>> report.fixed, report.step("holes").counts["holes_filled"], report.mass.after.volume
    (True, 1, 1.0)
    """
    from p3d_cli import measure
    from p3d_cli.measure import as_solid

    if weld is not None:
        weld = check_tolerance(weld)
    chosen = resolve_steps(steps, weld)
    required = _required(require)
    if not (float(flatness) >= 0):
        raise UsageError("flatness", f"{flatness!r} is not a non-negative number", "give a fraction such as 1e-3")
    if int(max_hole_edges) < 3:
        raise UsageError("max_hole_edges", f"{max_hole_edges!r} is below 3", "a hole has 3 edges at least")
    solid = as_solid(thing, format=format, stdin=stdin)
    mesh = solid.mesh
    if mesh is None:
        raise UsageError(solid.source, "is a shape spec, a clean solid by construction", "repair mesh files")
    where = mesh.where
    if mesh.tetrahedra is not None:
        raise InputError(where, "is a volume (tetrahedral) mesh; p3d repair mends triangle surfaces",
                         "export the boundary surface")
    if mesh.face_count == 0:
        raise InputError(where, "the mesh has no faces", "export it again with its faces")
    triangles = np.ascontiguousarray(mesh.triangles())
    outcome = repair_triangles(triangles, chosen, where=where, weld=weld, fill_holes=fill_holes,
                               flatness=float(flatness), max_hole_edges=int(max_hole_edges), required=required)
    out = outcome.triangles
    before = measure.props(triangles).properties
    after = measure.props(out).properties if outcome.changed else before
    notes = []
    if mesh.objects:
        notes.append(f"the file's {len(mesh.objects)} {mesh.object_kind or 'objects'} were repaired and are "
                     "written as one mesh, in their placed coordinates")
    if mesh.length_unit:
        notes.append(f"coordinates and mass properties are in the file's unit ({mesh.length_unit})")
    report = RepairReport(solid.source, mesh.format, outcome.steps, outcome.before, outcome.after,
                          MassChange(before, after), changed=outcome.changed,
                          unfixed=outcome.unfixed, notes=tuple(notes), required=required)
    return RepairedMesh(out, mesh.coordinate_dtype, outcome.draft), report


def _required(require: Iterable[str] | None) -> tuple[str, ...]:
    """The required checks, validated (``UsageError`` naming ``require``)."""
    from p3d_cli.mesh.verdicts import CHECKS

    if require is None:
        return tuple(CHECKS)
    names = tuple(dict.fromkeys([require] if isinstance(require, str) else require))
    unknown = [name for name in names if name not in CHECKS]
    if unknown:
        raise UsageError("require", f"no check named {unknown[0]!r}", "checks are: " + ", ".join(CHECKS))
    return names


def _what_is_not_carried(report: RepairReport, source: str, in_place: bool) -> RepairReport:
    """The report with a note of what the input holds that the output will not (colours,
    texture coordinates, ...: ``p3d_cli.io.carried``); in place, such a loss is refused.

    Raises
    ------
    OutputError
    """
    if source == "-" or not os.path.isfile(source):
        return report
    from p3d_cli.io.carried import extras

    lost = extras(source, report.format)
    if not lost:
        return report
    if in_place:
        from p3d_cli.errors import OutputError

        raise OutputError(source, "repairing it in place would drop its " + ", ".join(lost),
                          "write the repair to another file with output= (p3d writes positions and faces only)")
    return dataclasses.replace(report, notes=report.notes + ("not carried into the output: the input's "
                                                             + ", ".join(lost),))


def repair_file(source: str | os.PathLike, output: str | os.PathLike | None = None, *, in_place: bool = False,
                only_if_needed: bool = False, output_format: str | None = None,
                max_volume_change: float | None = None, steps: Iterable[str] | str | None = None,
                weld: float | None = None, fill_holes: str = "flat", flatness: float = FLATNESS,
                max_hole_edges: int = MAX_EDGES, require: Iterable[str] | None = None, format: str | None = None,
                stdin: BinaryIO | None = None, create_folders: bool = False) -> RepairReport:
    """Repair one file and write the result: what ``p3d repair`` does for each input.

    The output is written whole or not at all (``p3d_cli.io.atomic``); an output that is one of
    the inputs is refused unless ``in_place``. When nothing needs repair the input is copied
    byte for byte (or, in another format, converted), or nothing is written with
    ``only_if_needed``. When the relative volume change is over ``max_volume_change`` nothing is
    written (``report.written == "refused"``). A repair that leaves some check failing is still
    written (the report's ``unfixed`` says what remains).

    Parameters
    ----------
    source : path or ``-``
    output : path, optional
        Where to write (format from its extension, or ``output_format``); None with
        ``in_place`` False writes nothing (a dry run).
    in_place : bool
        Replace ``source`` itself (atomically), in its own format (an ASCII STL as ASCII STL);
        refused when the file holds what p3d does not write (colours, texture coordinates,
        ``p3d_cli.io.carried``).
    only_if_needed : bool
        Write nothing when nothing needs repair.
    output_format : str, optional
        ``stl`` (binary), ``ply``, ``obj`` or ``off``.
    max_volume_change : float, optional
        The largest relative volume change allowed (``|after - before| / |before|``).
    steps, weld, fill_holes, flatness, max_hole_edges, require, format, stdin
        As for ``repair``.
    create_folders : bool
        Create the output's missing folders (a batch mirroring its inputs' tree).

    Returns
    -------
    RepairReport
        With ``output``, ``written`` and ``max_volume_change`` set; ``report.ok`` is the exit
        status 0 of ``p3d repair``.

    Raises
    ------
    UsageError, InputError, OutputError
    """
    from p3d_cli.io.atomic import destination, replacing
    from p3d_cli.io.writers import output_format as format_of
    from p3d_cli.io.writers import write_mesh

    if max_volume_change is not None and not float(max_volume_change) >= 0:
        raise UsageError("max_volume_change", f"{max_volume_change!r} is not a non-negative number",
                         "give a relative change such as 1e-6")
    name = os.fspath(source)
    if in_place:
        if output is not None:
            raise UsageError("output, in_place", "both given", "give one: in_place writes over the input")
        if output_format is not None:
            raise UsageError("output_format, in_place", "both given", "in place, a file keeps its own format")
        if name == "-":
            raise UsageError("in_place", "standard input cannot be repaired in place", "give an output path")
        output = name
    inputs = [] if name == "-" else [name]
    target_format = None
    if output is not None:
        # Refused before the work: an output p3d cannot write, or must not write over.
        if not (in_place and output_format is None):
            target_format = format_of(output, output_format)
        if create_folders:
            os.makedirs(os.path.dirname(os.path.abspath(output)), exist_ok=True)
        destination(output, inputs=inputs, in_place=in_place, what="the repaired mesh")
    mesh, report = repair(source, steps, weld, fill_holes=fill_holes, flatness=flatness,
                          max_hole_edges=max_hole_edges, require=require, format=format, stdin=stdin)
    if in_place and target_format is None:
        # In place: the input's own format (its extension may name none).
        family = report.format.split("-")[0]
        target_format = format_of(output or name, family if family in ("stl", "ply", "obj", "off") else None)
    limit = None if max_volume_change is None else float(max_volume_change)
    report = dataclasses.replace(report, output=None if output is None else os.fspath(output),
                                 max_volume_change=limit)
    if output is None:
        return dataclasses.replace(report, written="dry run")
    if not report.within_limit:
        return dataclasses.replace(report, written="refused")
    if not report.changed:
        if in_place:
            return dataclasses.replace(report, written="unchanged")
        if only_if_needed:
            return dataclasses.replace(report, written="not written")
        if name != "-" and report.format.split("-")[0] == target_format:
            with replacing(output, inputs=inputs, what="the repaired mesh") as f, open(name, "rb") as original:
                shutil.copyfileobj(original, f, 1 << 20)
            return dataclasses.replace(report, written="copied")
    report = _what_is_not_carried(report, name, in_place)
    if target_format == "stl":      # triangles only: no vertex list to build
        write_mesh(output, None, None, triangles=mesh.triangles, format=target_format, inputs=inputs,
                   in_place=in_place, what="the repaired mesh", ascii_stl=in_place and report.format == "stl-ascii")
    else:
        write_mesh(output, mesh.vertices, mesh.faces, triangles=mesh.triangles, format=target_format,
                   inputs=inputs, in_place=in_place, what="the repaired mesh")
    return dataclasses.replace(report, written="written")
