"""A mesh's closed shells as the bodies of an assembly, and what ``p3d props`` says about them.

A multi-body STL (what CAD exports of assemblies write) is one triangle soup whose closed
shells are the bodies. ``p3d props --shells`` measures each body as a part of an assembly:
a body is a closed shell wound like the whole, together with the shells directly inside it
wound opposite to it (its cavities), so a hollow part is one part with its true volume. What
no closed shell holds (open or non-manifold pieces) is one more part. How the shells nest is
``p3d_cli.mesh.nesting``'s; whether they cross, ``p3d_cli.mesh.intersections``'.

``p3d props`` also states, with a stable code, what the exact test finds: ``self-intersecting``
when faces cross or overlap (the common region is counted twice), ``nested-shells`` when a
shell lies in another wound alike (its volume is counted twice) or a cavity lies in no body.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from p3d_cli.io.source import MeshSource, array_source
from p3d_cli.mesh.layout import Layout
from p3d_cli.mesh.report import TopologyReport
from p3d_cli.results import PropsResult
from p3d_cli.warning_codes import CodedWarning


def solidity(mesh: MeshSource) -> tuple[TopologyReport, Layout | None]:
    """The topology of ``mesh`` with its self-intersections and its shells' nesting."""
    from p3d_cli.mesh.solidity import with_solidity
    from p3d_cli.mesh.topology import topology_and_layout

    report, layout = topology_and_layout(mesh.read_blocks, mesh.face_count, mesh.where, edges=False)
    if layout is not None:
        report = with_solidity(report, mesh.read_blocks, layout)
    return report, layout


_VERBS = {"crossing": "cross", "overlap": "overlap", "fold": "fold"}


def solidity_warnings(report: TopologyReport) -> list[CodedWarning]:
    """The ``self-intersecting`` and ``nested-shells`` warnings for what the exact test found."""
    out: list[CodedWarning] = []
    found, nesting = report.self_intersections, report.nesting
    if found is not None and found.count:
        first = found.samples[0]
        where = ", ".join(f"{x:.7g}" for x in first.point)
        bound = "" if nesting is None or not nesting.crossing_bound else \
            f" (where closed shells cross, at most {nesting.crossing_bound:.6g})"
        out.append(CodedWarning(
            f"the surface intersects itself: {found.count} face pair{'s' if found.count != 1 else ''} cross or "
            f"overlap (e.g. faces {first.faces[0]} and {first.faces[1]} {_VERBS[first.kind]} at ({where})), so the "
            f"faces bound no solid and a region they enclose together is counted twice{bound}; "
            "p3d check lists them", "self-intersecting"))
    if nesting is not None:
        for place in nesting.shells:
            if place.inside is not None and abs(place.winding) >= 2:
                out.append(CodedWarning(
                    f"closed shell {place.shell} (from face {place.first_face}) lies inside shell {place.inside} and "
                    f"is wound alike: its volume ({abs(place.volume):.6g}) is counted {abs(place.winding)} times; "
                    "reverse its winding if it is a cavity, or remove it if it is a copy", "nested-shells"))
        if nesting.counted_negative:
            out.append(CodedWarning(
                f"a closed shell wound as a cavity lies in no body: a volume of {nesting.counted_negative:.6g} is "
                "counted negative; reverse its winding", "nested-shells"))
    return out


def with_solidity_warnings(result: PropsResult, mesh: MeshSource) -> PropsResult:
    """``result`` with the exact test's warnings; they replace the inertia heuristic's
    ``self-intersecting`` ("probably intersects itself") when the test finds a crossing."""
    report, _ = solidity(mesh)
    if mesh.length_unit is not None:                # props reports such a file in metres
        from p3d_cli.units import LENGTHS

        report = report.in_length_unit(LENGTHS[mesh.length_unit])
    extra = solidity_warnings(report)
    if not extra:
        return result
    exact_code = {getattr(w, "code", None) for w in extra}
    kept = [w for w, code in zip(result.warnings, result.warning_codes)
            if not (code == "self-intersecting" and code in exact_code)]
    return dataclasses.replace(result, warnings=tuple(kept + extra))


def shell_parts(mesh: MeshSource) -> tuple[list[tuple[str, MeshSource]], list[CodedWarning]]:
    """Each body of ``mesh`` as ``(name, MeshSource)``, and the exact test's warnings."""
    report, layout = solidity(mesh)
    warnings = solidity_warnings(report)
    if layout is None or report.nesting is None:
        return [("shell 0", mesh)], warnings
    nesting = report.nesting
    labels = layout.shells.labels
    parent = dict(nesting.parent)
    sign = 1.0 if report.volume >= 0 else -1.0
    # Each closed shell wound like the whole heads a body; a shell wound the other way joins
    # the body directly around it (a cavity), or is a body of its own if none holds it.
    body = {}
    for s, outer in parent.items():
        heads = np.sign(nesting.volumes[s]) == sign or outer is None
        body[s] = s if heads else outer
    groups = np.full(layout.shells.count, -1, dtype=np.int64)
    for s, head in body.items():
        groups[s] = head
    face_group = groups[labels]
    triangles = mesh.triangles()
    parts = []
    for head in sorted(set(body.values())):
        members = np.flatnonzero(face_group == head)
        cavities = [s for s, h in body.items() if h == head and s != head]
        name = f"shell {head}" + (f" with cavit{'ies' if len(cavities) > 1 else 'y'} "
                                  + ", ".join(map(str, cavities)) if cavities else "")
        parts.append((name, _source(mesh, triangles[members], f"{mesh.where} (shell {head})")))
    rest = np.flatnonzero(face_group < 0)
    if rest.size:
        parts.append(("open shells", _source(mesh, triangles[rest], f"{mesh.where} (open shells)")))
    return parts, warnings


def _source(mesh: MeshSource, triangles: np.ndarray, where: str) -> MeshSource:
    return dataclasses.replace(array_source(mesh.format, triangles, mesh.coordinate_dtype), where=where,
                               length_unit=mesh.length_unit)


def shells_assembly(solid, scene):
    """``props(shells=True)``: the assembly of ``solid``'s bodies, and the exact test's warnings.

    Raises
    ------
    UsageError
        ``solid`` is a shape, a volume mesh, or a file of several objects (already parts).
    """
    from p3d_cli.errors import UsageError
    from p3d_cli.measure.assembly.parts import Assembly, Part

    mesh = solid.mesh
    if mesh is None or mesh.tetrahedra is not None or scene is not None:
        what = ("a shape spec" if mesh is None else "a volume mesh" if mesh.tetrahedra is not None
                else f"a file of {len(mesh.objects)} objects, measured as parts already")
        raise UsageError("shells", f"{solid.source} is {what}", "shells= applies to one triangle mesh")
    parts, warnings = shell_parts(mesh)
    return Assembly(solid.source, tuple(Part(name, source, where=source.where) for name, source in parts),
                    mesh.length_unit), warnings
