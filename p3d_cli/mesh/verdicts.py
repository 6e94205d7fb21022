"""``p3d check``'s verdicts: the named checks, and one mesh's result against them."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from p3d_cli.mesh.report import TopologyReport
from p3d_cli.mesh.topology import topology_and_layout
from p3d_cli.mesh.weld import Weld
from p3d_cli.records import Record

#: The checks ``p3d check --require`` can ask for, and what each needs.
CHECKS = {
    "closed": "every edge used by exactly two faces, in opposite directions",
    "oriented": "no edge used twice in the same direction",
    "outward": "positive total signed volume (faces wound counter-clockwise seen from outside)",
    "manifold": "no edge used by more than two faces, no vertex joining separate fans of faces",
    "no-degenerate": "no face with zero area or a repeated vertex",
    "no-duplicate": "no two faces with the same three vertices",
    "no-self-intersection": "no two faces whose interiors cross or overlap (decided exactly)",
    "nesting": "closed shells nest as a solid's: a shell inside another is wound opposite to it (a cavity), "
               "so no volume is counted twice",
}

#: The counts of defects the record and the text verdict give, each with its noun and the
#: ``TopologyReport`` field of its sample locations.
SAMPLED_COUNTS = (("boundary_edges", "boundary edge", "boundary_edge_samples"),
                  ("nonmanifold_edges", "non-manifold edge", "nonmanifold_edge_samples"),
                  ("misoriented_edges", "misoriented edge", "misoriented_edge_samples"),
                  ("nonmanifold_vertices", "non-manifold vertex", "nonmanifold_vertex_samples"),
                  ("degenerate_faces", "degenerate face", "degenerate_face_samples"),
                  ("duplicate_faces", "duplicate face", "duplicate_face_samples"))

#: The checks that need the self-intersection pass (the costliest: run only when required).
SOLIDITY = ("no-self-intersection", "nesting")


def passes(report: TopologyReport, check: str) -> bool:
    """Whether ``report`` passes the named check (a key of ``CHECKS``)."""
    if check == "closed":
        return report.closed
    if check == "oriented":
        return report.oriented
    if check == "outward":
        return report.volume > 0
    if check == "manifold":
        return report.manifold
    if check == "no-degenerate":
        return report.degenerate_faces == 0
    if check == "no-duplicate":
        return report.duplicate_faces == 0
    if check == "no-self-intersection":
        return report.self_intersections is not None and report.self_intersections.count == 0
    if check == "nesting":
        return report.nesting is not None and report.nesting.ok
    raise KeyError(check)


@dataclass(frozen=True)
class CheckResult(Record):
    """One mesh's verdict.

    Attributes
    ----------
    source : str
    format : str
    report : TopologyReport
    required : tuple of str
        The checks asked for (keys of ``CHECKS``).
    failed : tuple of str
        The required checks that failed, then ``min-volume`` / ``max-faces`` if a limit was
        broken, then ``NAME:CHECK`` for each check an object of a multi-object file failed.
    parts : tuple of (str, CheckResult)
        For a file of several objects (glTF nodes, 3MF build items), each object's verdict.
    weld : Weld or None
        With a weld tolerance: what was merged before the checks (``p3d_cli.mesh.weld``).
    declared_unit : str or None
        The unit the file declares (glTF, 3MF, DAE, AMF; a key of ``p3d_cli.units.LENGTHS``):
        the report's lengths and volumes are then in metres, as ``props`` reports them; None:
        in the mesh's own unit.
    """

    source: str
    format: str
    report: TopologyReport
    required: tuple[str, ...]
    failed: tuple[str, ...]
    parts: tuple = ()
    weld: Weld | None = None
    declared_unit: str | None = None

    @property
    def ok(self) -> bool:
        return not self.failed

    # One step to the report's common quantities.
    @property
    def volume(self) -> float:
        """``report.solid_volume``: the enclosed solid's, positive for an inward-wound mesh (as props)."""
        return self.report.solid_volume

    @property
    def faces(self) -> int:
        """``report.faces``."""
        return self.report.faces

    @property
    def closed(self) -> bool:
        """``report.closed``."""
        return self.report.closed

    @property
    def manifold(self) -> bool:
        """``report.manifold``."""
        return self.report.manifold

    def _record(self) -> dict[str, Any]:
        return check_record(self)

    def _repr_html_(self) -> str:
        """In a notebook: the verdict, the counts, and the mesh with its defects drawn."""
        from p3d_cli.render.notebook import check_html

        return check_html(self)


def check_source(mesh, source: str, required=tuple(CHECKS), min_volume: float | None = None,
                 max_faces: int | None = None, weld: float | None = None,
                 declared_unit: str | None = None) -> CheckResult:
    """Check a loaded mesh against the required checks and limits.

    The triangles are read block by block (twice, and once more for the volumes of several
    shells), never held whole.

    Parameters
    ----------
    mesh : p3d_cli.io.MeshSource
    source : str
        The input's name (``-`` for standard input).
    required : iterable of str
        Keys of ``CHECKS``.
    min_volume : float, optional
        Fail when the total signed volume is below this.
    max_faces : int, optional
        Fail when the mesh has more faces than this.
    weld : float, optional
        Merge vertices within this distance (the file's units) before the checks; never done
        without it (``p3d_cli.mesh.weld``).
    declared_unit : str, optional
        The unit the file declares (``MeshSource.length_unit``): lengths and volumes (and
        ``min_volume``'s comparison) are then in metres.

    Raises
    ------
    InputError
        A volume mesh, no faces, or a NaN or infinite coordinate.
    """
    from p3d_cli.errors import InputError

    where = "<stdin>" if source == "-" else source
    if mesh.tetrahedra is not None:
        raise InputError(where, "is a volume (tetrahedral) mesh; p3d check inspects triangle surfaces",
                         "export the boundary surface")
    if mesh.face_count == 0:
        raise InputError(where, "the mesh has no faces", "export it again with its faces")
    welded = None
    if weld is not None:
        from p3d_cli.io.source import array_source
        from p3d_cli.mesh.weld import weld_triangles

        triangles, welded = weld_triangles(_finite(mesh, where), weld)
        mesh = array_source(mesh.format, triangles, "float64")
    report, layout = topology_and_layout(mesh.read_blocks, mesh.face_count, where, edges=False)
    required = tuple(required)
    if any(name in required for name in SOLIDITY) and layout is not None:
        from p3d_cli.mesh.solidity import with_solidity

        report = with_solidity(report, mesh.read_blocks, layout)
    if declared_unit is not None:
        from p3d_cli.units import LENGTHS

        report = report.in_length_unit(LENGTHS[declared_unit])
    failed = [name for name in required if not passes(report, name)]
    if min_volume is not None and not report.volume >= min_volume:
        failed.append("min-volume")
    if max_faces is not None and report.faces > max_faces:
        failed.append("max-faces")
    return CheckResult(source, mesh.format, report, required, tuple(failed), weld=welded,
                       declared_unit=declared_unit)


def _finite(mesh, where: str):
    """All of ``mesh``'s triangles, refusing a NaN or infinite coordinate (``InputError``)."""
    import numpy as np

    from p3d_cli.io.source import first_nonfinite, nonfinite_error

    triangles = mesh.triangles()
    bad = first_nonfinite(triangles)
    if bad is not None:
        raise nonfinite_error(where, bad)
    return np.asarray(triangles, dtype=np.float64)


def check_record(result: CheckResult) -> dict:
    """The JSON object of ``p3d check`` for one input (stable keys)."""
    r = result.report
    record = {
        "source": result.source,
        "format": result.format,
        "ok": result.ok,
        "failed": list(result.failed),
        "required": list(result.required),
        "faces": r.faces,
        "vertices": r.vertices,
        "edges": r.edges,
        "closed": r.closed,
        "oriented": r.oriented,
        "outward": r.volume > 0,
        "manifold": r.manifold,
    }
    for key, _, _ in SAMPLED_COUNTS:
        record[key] = getattr(r, key)
    record.update({
        "zero_area_faces": r.zero_area_faces,
        "faces_with_repeated_vertex": r.faces_with_repeated_vertex,
        "shells": r.shells,
        "shell_list": [{"faces": s.faces, "first_face": s.first_face, "volume": s.volume}
                       for s in r.shell_list],
        # The volume props reports (the enclosed solid's, positive for an inward mesh) and the
        # faces' signed volume, in the same units as props.
        "volume": r.solid_volume,
        "signed_volume": r.volume,
        "units": ({"length": "m", "volume": "m^3", "mesh_length": result.declared_unit} if result.declared_unit
                  else {"length": "mesh unit", "volume": "mesh unit^3"}),
        "samples": {key: [_sample_json(s) for s in getattr(r, samples)] for key, _, samples in SAMPLED_COUNTS},
        "vertex_matching": "exact coordinates (no tolerance; -0.0 equals 0.0)",
        # None when the no-self-intersection check was not asked for (it is not computed then).
        "self_intersections": None if r.self_intersections is None else r.self_intersections.to_dict(),
        "nesting": None if r.nesting is None else r.nesting.to_dict(),
    })
    if result.weld is not None:
        record["weld"] = result.weld.to_dict()
    if result.parts:
        record["parts"] = [{"name": name, **check_record(part)} for name, part in result.parts]
    return record


def _sample_json(sample):
    if isinstance(sample, int):
        return sample
    if isinstance(sample, tuple):  # duplicate faces: (earlier face, later face)
        return list(sample)
    if hasattr(sample, "points"):
        return {"faces": list(sample.faces), "edge": [list(p) for p in sample.points]}
    return {"faces": list(sample.faces), "vertex": list(sample.point)}
