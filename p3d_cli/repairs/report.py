"""What ``p3d repair`` did: each step with its counts and locations, the check before and after,
and the mass properties before and after with their difference.

Face numbers are 0-based. A step that removes, flips or moves faces names them by their place
in the *input* (file order, polygons split into fans, as ``p3d check`` numbers them); faces a
step adds are named by their place in the *output* (they follow the input's faces that were
kept, in the order they were made).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from p3d_cli.mesh.report import TopologyReport
from p3d_cli.mesh.verdicts import CHECKS, SOLIDITY, passes
from p3d_cli.results import MassProperties

#: Locations listed per step in the text report (the record lists every face).
SHOWN = 5
#: Places (holes, merged vertices, repeated faces) a step's record describes one by one, and
#: notes it keeps; the counts and face numbers are always complete.
PLACES = 1000
NOTES = 20


@dataclass(frozen=True)
class StepReport:
    """One step of a repair.

    Attributes
    ----------
    name : str
        A key of ``p3d_cli.repairs.steps.STEPS``.
    ran : bool
        False when the step was not asked for, or had nothing to work on (the mesh passed
        ``check`` already).
    counts : dict
        What it changed, by kind (``faces_removed``, ``faces_flipped``, ``holes_filled``, ...).
    faces : tuple of int
        Input faces it removed, flipped or moved.
    new_faces : tuple of int
        Output faces it added.
    places : tuple of dict
        Where it acted or what it left, one record each (a hole: its edge count, centre, size,
        flatness, whether filled and why not; a shell: its first face, faces, volume); the
        first ``PLACES``.
    notes : tuple of str
        What it left as it was, and why (the first ``NOTES``).
    """

    name: str
    ran: bool = True
    counts: dict = field(default_factory=dict)
    faces: tuple[int, ...] = ()
    new_faces: tuple[int, ...] = ()
    places: tuple[dict, ...] = ()
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        notes = list(self.notes)
        if len(self.places) > PLACES:
            notes.append(f"{len(self.places) - PLACES} more places not described (the first {PLACES} are)")
            object.__setattr__(self, "places", tuple(self.places[:PLACES]))
        if len(notes) > NOTES:
            notes = notes[:NOTES - 1] + [f"and {len(notes) - NOTES + 1} more notes like these"]
        object.__setattr__(self, "notes", tuple(notes))

    @property
    def changes(self) -> int:
        """Faces this step removed, flipped, moved or added."""
        return len(self.faces) + len(self.new_faces)

    def to_dict(self) -> dict:
        """The step's record; face numbers as runs ``[first, last]`` (inclusive), so that a step
        that turns a million faces round says so in one pair."""
        return {"step": self.name, "ran": self.ran, "counts": dict(self.counts), "faces": runs(self.faces),
                "new_faces": runs(self.new_faces), "places": [dict(p) for p in self.places],
                "notes": list(self.notes)}


def runs(numbers) -> list[list[int]]:
    """``[[first, last], ...]``: ascending integers as runs of consecutive ones."""
    values = np.unique(np.asarray(numbers, dtype=np.int64))
    if values.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(values) != 1)
    starts = np.r_[values[0], values[breaks + 1]]
    ends = np.r_[values[breaks], values[-1]]
    return [[int(a), int(b)] for a, b in zip(starts.tolist(), ends.tolist())]


@dataclass(frozen=True)
class MassChange:
    """Mass properties (density 1, in the mesh's own units) before and after, and their change.

    ``before`` and ``after`` are what ``p3d props`` reports for the input and for the output:
    the enclosed solid's volume (positive for an inward-wound mesh too, as ``props`` reports
    it), centre of mass, inertia about it. An open input's numbers follow ``props``' convention
    for open surfaces (docs/method.md, "Open and non-manifold meshes").
    """

    before: MassProperties
    after: MassProperties

    @property
    def volume_change(self) -> float:
        """``after.volume - before.volume``."""
        return float(self.after.volume - self.before.volume)

    @property
    def relative_volume_change(self) -> float:
        """``|after - before| / |before|`` of the volume (inf when the input enclosed nothing
        and the output does; 0 when neither does)."""
        change = abs(self.volume_change)
        if change == 0:
            return 0.0
        return change / abs(self.before.volume) if self.before.volume != 0 else float("inf")

    @property
    def center_shift(self) -> float | None:
        """Distance the centre of mass moved (None when either has none)."""
        if self.before.center_of_mass is None or self.after.center_of_mass is None:
            return None
        return float(np.linalg.norm(self.after.center_of_mass - self.before.center_of_mass))

    @property
    def relative_inertia_change(self) -> float | None:
        """Largest change of an inertia component over the largest component before."""
        if self.before.inertia is None or self.after.inertia is None:
            return None
        scale = float(np.abs(self.before.inertia).max())
        change = float(np.abs(self.after.inertia - self.before.inertia).max())
        if change == 0:
            return 0.0
        return change / scale if scale else float("inf")

    def to_dict(self) -> dict:
        def props(p: MassProperties) -> dict:
            return {"volume": p.volume, "center_of_mass": p.center_of_mass, "inertia": p.inertia}

        def finite(x):        # a change from nothing has no relative size: null in the record
            return x if x is None or np.isfinite(x) else None

        return {"before": props(self.before), "after": props(self.after),
                "volume_change": self.volume_change,
                "relative_volume_change": finite(self.relative_volume_change),
                "center_shift": self.center_shift, "relative_inertia_change": finite(self.relative_inertia_change)}


def check_summary(report: TopologyReport, required=tuple(CHECKS)) -> dict:
    """The counts of ``p3d check`` for one mesh, the required checks it fails, and those not
    tested (the self-intersection tests of an input that fails others already)."""
    crossing = report.self_intersections.count if report.self_intersections is not None else None
    return {"failed": list(failed_checks(report, required)), "not_tested": list(untested(report, required)),
            "faces": report.faces, "vertices": report.vertices, "self_intersections": crossing,
            "boundary_edges": report.boundary_edges, "nonmanifold_edges": report.nonmanifold_edges,
            "misoriented_edges": report.misoriented_edges, "nonmanifold_vertices": report.nonmanifold_vertices,
            "degenerate_faces": report.degenerate_faces, "duplicate_faces": report.duplicate_faces,
            "shells": report.shells, "signed_volume": report.volume}


def untested(report: TopologyReport, required=tuple(CHECKS)) -> tuple[str, ...]:
    """The required checks ``report`` holds no answer to (self-intersections not computed)."""
    return tuple(name for name in required if name in SOLIDITY and report.self_intersections is None)


def failed_checks(report: TopologyReport, required=tuple(CHECKS)) -> tuple[str, ...]:
    """The required checks of ``p3d check`` (default: all) that ``report`` fails; a check it
    holds no answer to (``untested``) is not counted failed."""
    skip = untested(report, required)
    return tuple(name for name in required if name not in skip and not passes(report, name))


@dataclass(frozen=True)
class RepairReport:
    """Everything a repair changed, and what it could not.

    Attributes
    ----------
    source : str
        The input as given.
    format : str
        The input's format (``MeshSource.format``).
    steps : tuple of StepReport
        Every step in its order, run or not.
    before, after : TopologyReport
        ``p3d check``'s topology of the input and of the output (the output's decides whether
        it is fixed).
    mass : MassChange
    changed : bool
        Whether any face was removed, flipped, moved or added.
    unfixed : tuple of str
        What the output still fails, each with the reason repair left it.
    notes : tuple of str
        Anything else the user should know (a multi-object file repaired as one mesh).
    output : str or None
        Where the output was written (``repair_file``), or None.
    written : str
        What ``repair_file`` did with the output: ``written``, ``copied`` (the input, byte for
        byte: nothing to repair), ``not written`` (with ``only_if_needed``), ``refused`` (a
        limit was broken), ``dry run``; empty for ``repair``.
    max_volume_change : float or None
        The limit ``repair_file`` held the relative volume change to.
    required : tuple of str
        The checks of ``p3d check`` the output must pass to be called fixed (default: all).
    """

    source: str
    format: str
    steps: tuple[StepReport, ...]
    before: TopologyReport
    after: TopologyReport
    mass: MassChange
    changed: bool
    unfixed: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    output: str | None = None
    written: str = ""
    max_volume_change: float | None = None
    required: tuple[str, ...] = tuple(CHECKS)

    @property
    def failed_before(self) -> tuple[str, ...]:
        return failed_checks(self.before, self.required)

    @property
    def failed_after(self) -> tuple[str, ...]:
        return failed_checks(self.after, self.required)

    @property
    def fixed(self) -> bool:
        """The output passes every required check of ``p3d check`` (the input did, or repair
        made it)."""
        return not self.failed_after and not untested(self.after, self.required)

    @property
    def within_limit(self) -> bool:
        """The relative volume change is within ``max_volume_change`` (True without one)."""
        return self.max_volume_change is None or self.mass.relative_volume_change <= self.max_volume_change

    @property
    def ok(self) -> bool:
        """Fixed, and within the volume limit: the exit status 0 of ``p3d repair``."""
        return self.fixed and self.within_limit

    def step(self, name: str) -> StepReport:
        """The report of the step called ``name``."""
        return next(s for s in self.steps if s.name == name)

    def to_dict(self) -> dict:
        """The JSON record of ``p3d repair --json`` (stable keys)."""
        return {"source": self.source, "format": self.format, "ok": self.ok, "fixed": self.fixed,
                "changed": self.changed, "output": self.output, "written": self.written,
                "max_volume_change": self.max_volume_change, "within_limit": self.within_limit,
                "required": list(self.required), "before": check_summary(self.before, self.required),
                "after": check_summary(self.after, self.required),
                "steps": [s.to_dict() for s in self.steps], "mass": self.mass.to_dict(),
                "unfixed": list(self.unfixed), "notes": list(self.notes),
                "units": {"length": "mesh unit", "volume": "mesh unit^3"},
                "vertex_matching": "exact coordinates (no tolerance; -0.0 equals 0.0) unless weld is given"}
