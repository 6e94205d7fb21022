"""The repair of one mesh: ``p3d check``'s topology, the steps in their order, the check again.

1. The input's topology is ``p3d check``'s (``p3d_cli.mesh.topology``): a mesh it passes is
   returned untouched, whatever steps were asked for.
2. Otherwise the faces become a ``Draft`` on ``check``'s exact vertex ids, and the steps run in
   the order of ``p3d_cli.repairs.steps.STEPS``, each on the draft the one before left. They
   start from what the topology found (``topology_and_layout``: vertex ids, shells, zero-area
   and duplicate faces, the edge grouping); the edges are grouped again, by ``check``'s own edge
   code, only when faces were removed or moved (``p3d_cli.repairs.draft.grouping``), and the
   orientation, the holes and the shells all read that one grouping.
3. The output's topology is ``check``'s again: the output is *fixed* exactly when ``p3d check``
   would pass it. Whatever it still fails is listed with the reason each step left it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.io.source import array_source
from p3d_cli.mesh.layout import Layout
from p3d_cli.mesh.report import TopologyReport
from p3d_cli.mesh.solidity import with_solidity
from p3d_cli.mesh.topology import topology_and_layout
from p3d_cli.mesh.verdicts import CHECKS, SOLIDITY
from p3d_cli.repairs.cleanup import degenerate_step, duplicate_step, weld_step
from p3d_cli.repairs.draft import Draft, Grouping, grouping, with_directions
from p3d_cli.repairs.fill import FLATNESS, MAX_EDGES, POLICIES
from p3d_cli.repairs.holes import Holes, holes_step
from p3d_cli.repairs.orient import Patches, joined, orient_step, outward_step, patches
from p3d_cli.repairs.report import SHOWN, StepReport, failed_checks
from p3d_cli.repairs.steps import STEPS


@dataclass(frozen=True)
class Outcome:
    """One mesh repaired (internal: what ``p3d_cli.repairs.repair`` makes its report of).

    Attributes
    ----------
    draft : Draft or None
        The repaired faces; None when no vertex ids were needed (nothing changed, or every face
        was turned round).
    triangles : (k, 3, 3)
        The output's triangles (``Draft.output_triangles``; the input's when nothing changed).
    before, after : TopologyReport
    steps : tuple of StepReport
        Every step, in order.
    unfixed : tuple of str
    changed : bool
        Whether any face was removed, flipped, moved or added.
    """

    draft: Draft | None
    triangles: np.ndarray
    before: TopologyReport
    after: TopologyReport
    steps: tuple[StepReport, ...]
    unfixed: tuple[str, ...]
    changed: bool


def repair_triangles(triangles: np.ndarray, steps: tuple[str, ...], *, where: str = "<array>",
                     weld: float | None = None, fill_holes: str = "flat", flatness: float = FLATNESS,
                     max_hole_edges: int = MAX_EDGES, required: tuple[str, ...] = tuple(CHECKS)) -> Outcome:
    """Repair a triangle soup.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64
        The input's triangles, as stored.
    steps : tuple of str
        The steps to run (``resolve_steps``' answer).
    where : str
        The input's name in messages (a NaN or infinite coordinate is an ``InputError`` there).
    weld, fill_holes, flatness, max_hole_edges
        As for ``p3d_cli.repairs.repair``.
    required : tuple of str
        The checks of ``p3d check`` that decide whether the mesh needs repair and whether the
        output is fixed (keys of ``p3d_cli.mesh.verdicts.CHECKS``; default all).
    """
    if fill_holes not in POLICIES:
        from p3d_cli.errors import UsageError

        raise UsageError("fill_holes", f"unknown policy {fill_holes!r}", "use " + " or ".join(POLICIES))
    n = len(triangles)
    # In blocks, as a file is read (the topology's passes are tuned to cache-sized blocks).
    blocks = array_source("array", triangles, str(triangles.dtype)).read_blocks
    before, layout = topology_and_layout(blocks, n, where)
    assert layout is not None                   # n > 0
    if any(name in SOLIDITY for name in required) and not failed_checks(before, required):
        # Its topology passes: whether it crosses itself decides whether it needs repair. (An
        # input failing a topology check is repaired first; its output's crossings are tested.)
        before = with_solidity(before, blocks, layout)
    if not failed_checks(before, required):
        clean = tuple(StepReport(name, ran=False, notes=("the mesh passes p3d check: nothing to do",)
                                   if name in steps else ()) for name in STEPS)
        return Outcome(None, triangles, before, before, clean, (), False)
    if _only_inward(before, steps):
        return _turned_out(triangles, before, steps, required)
    # check's exact vertex ids, shells, zero-area and duplicate faces and edges: the steps
    # start from what the topology found, and group again only faces it did not see.
    ids, points = _vertices(layout, triangles)
    draft = Draft.of(triangles, ids, points)
    reports = {name: StepReport(name, ran=False) for name in STEPS}
    if "weld" in steps:
        draft, reports["weld"] = weld_step(draft, float(weld or 0))
    moved = bool(draft.moved.any())
    if "degenerate" in steps:
        if before.degenerate_faces or moved:
            draft, reports["degenerate"] = degenerate_step(draft, None if moved else layout.zero_area)
        else:
            reports["degenerate"] = StepReport("degenerate", counts={"faces_removed": 0})
    if "duplicate" in steps:
        if before.duplicate_faces or moved:
            known = None if moved or layout.duplicates is None else layout.duplicates
            draft, reports["duplicate"] = duplicate_step(draft, known)
        else:
            reports["duplicate"] = StepReport("duplicate", counts={"faces_removed": 0})
    as_input = len(draft.faces) == n and not draft.moved.any()
    grouped = _grouping(draft, layout, as_input)
    filled: Holes | None = None
    if grouped is None:
        # Every edge of the input used once each way and the same faces: its shells are the
        # patches, consistent and closed; nothing for orient or holes.
        found = _as_patches(layout)
        for name, counts in (("orient", {"faces_flipped": 0, "shells": 0}),
                             ("holes", {"holes_filled": 0, "holes_left": 0, "faces_added": 0})):
            if name in steps:
                reports[name] = StepReport(name, counts=counts)
        holes_left: tuple[str, ...] = ()
        open_faces = np.zeros(0, dtype=np.int64)
    else:
        # Without a misoriented or non-manifold edge the patches are check's shells.
        consistent = grouped.edges.misoriented.size == 0 and grouped.edges.nonmanifold.size == 0
        found = _as_patches(layout) if as_input and consistent else patches(len(draft.faces), grouped.edges)
        if "orient" in steps:
            draft, reports["orient"] = orient_step(draft, found)
        holes_left = ()
        open_faces = _open_faces(grouped, "orient" in steps)
        if "holes" in steps:
            draft, reports["holes"], holes = holes_step(draft, grouped, policy=fill_holes, flatness=flatness,
                                                        max_edges=max_hole_edges)
            holes_left = reports["holes"].notes
            filled = holes
            found = joined(found, holes.holes)
            open_faces = np.union1d(_open_faces(grouped, "orient" in steps, boundary=False), holes.open_faces)
    shells_left: tuple[str, ...] = ()
    out = draft.output_triangles()
    fillings = filled.fillings(len(out)) if filled is not None else None
    if "outward" in steps:
        open_patches = np.unique(found.labels[open_faces])
        draft, reports["outward"], turned = outward_step(draft, out, found, open_patches)
        out[turned] = out[turned][:, [0, 2, 1]]
        shells_left = reports["outward"].notes
    after = checked(out, required, fillings, filled.nearby if filled is not None else None)
    ordered = tuple(reports[name] for name in STEPS)
    return Outcome(draft, out, before, after, ordered, unfixed(after, steps, required, holes_left, shells_left),
                   draft.changed)


def checked(triangles: np.ndarray, required: tuple[str, ...], fillings: np.ndarray | None = None,
            nearby: np.ndarray | None = None) -> TopologyReport:
    """``p3d check``'s report of the output: its topology, and its self-intersections and
    shells' nesting when those are required (``p3d_cli.mesh.solidity``), in the blocks a file
    of it would be read in. ``fillings`` labels the faces of each hole filled on a coordinate
    plane (``Holes.fillings``): the pair test would find their pairs within one filling
    ``NONE``, so they are left out (the report is the same). ``nearby`` (``Holes.nearby``, in
    the output's numbering): every face near a filling face, found when the fillings were
    tested; the fillings' faces are paired with those only, not by the broad phase, whose boxes
    of slivers hold many faces they miss (the report is the same)."""
    blocks = array_source("array", triangles, str(triangles.dtype)).read_blocks
    # Nothing after reads the output's grouped edges: the fast path may take its boundary.
    report, layout = topology_and_layout(blocks, len(triangles), edges=False)
    if any(name in SOLIDITY for name in required) and layout is not None:
        report = with_solidity(report, blocks, layout, fillings, nearby)
    return report


def _only_inward(before: TopologyReport, steps: tuple[str, ...]) -> bool:
    """Whether the input's one fault is being one shell wound inward: every edge used once
    each way, nothing to remove or weld, and a negative volume."""
    return (before.shells == 1 and before.volume < 0 and "outward" in steps and "weld" not in steps
            and before.closed and before.degenerate_faces == 0 and before.duplicate_faces == 0)


def _turned_out(triangles: np.ndarray, before: TopologyReport, steps: tuple[str, ...],
                required: tuple[str, ...]) -> Outcome:
    """One closed shell wound inward: every face turned round, with no vertex ids or edges
    needed; the output checked as any other."""
    n = len(triangles)
    out = triangles[:, [0, 2, 1]]
    after = checked(out, required)
    reports = {name: StepReport(name, ran=name in steps) for name in STEPS}
    for name, counts in (("degenerate", {"faces_removed": 0}), ("duplicate", {"faces_removed": 0}),
                         ("orient", {"faces_flipped": 0, "shells": 0}),
                         ("holes", {"holes_filled": 0, "holes_left": 0, "faces_added": 0})):
        if name in steps:
            reports[name] = StepReport(name, counts=counts)
    reports["outward"] = StepReport(
        "outward", counts={"shells_flipped": 1, "faces_flipped": n, "closed_shells": 1, "cavities": 0},
        faces=tuple(range(n)), places=({"shell_first_face": 0, "faces": n, "signed_volume_before": before.volume,
                                         "cavity": False},))
    return Outcome(None, out, before, after, tuple(reports[name] for name in STEPS),
                   unfixed(after, steps, required, (), ()), True)


def _vertices(layout: Layout, triangles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The topology's vertex ids ``(3n,)`` numbered densely, and the coordinates of each.

    The fast path's ids are not all used (a vertex of several fans takes its first fan's id):
    the steps take every row of ``points`` for a vertex (the weld step merges them), so the
    unused ids go; the order of the others is kept."""
    ids = layout.ids
    used = np.zeros(layout.vertex_count, dtype=bool)
    used[ids] = True
    if not used.all():
        dense = np.cumsum(used) - 1
        ids = dense[ids]
    points = np.empty((int(ids.max()) + 1, 3), dtype=triangles.dtype)
    points[ids] = triangles.reshape(-1, 3)
    return ids, points


def _as_patches(layout: Layout) -> Patches:
    """The topology's shells as patches wound consistently (nothing to flip)."""
    n = len(layout.shells.labels)
    return Patches(layout.shells.labels, layout.shells.count, np.zeros(n, dtype=bool), np.zeros(0, dtype=np.int64))


def _grouping(draft: Draft, layout: Layout, as_input: bool) -> Grouping | None:
    """The draft's edges: the topology's own while its faces are the input's (None when the
    topology grouped none: every edge used once each way), else grouped anew."""
    if not as_input:
        return grouping(draft)
    if layout.edges is None:
        return None
    return Grouping(with_directions(layout.edges, layout.ids), draft.faces, draft.flipped.copy())


def _open_faces(grouped: Grouping, oriented: bool, boundary: bool = True) -> np.ndarray:
    """Faces on an edge that keeps their patch from being closed: a non-manifold edge, a
    boundary edge (unless the holes step answers for those), a misoriented edge (unless the
    orient step mended them)."""
    edges = grouped.edges
    groups = [edges.nonmanifold]
    if boundary:
        groups.append(edges.boundary)
    if not oriented:
        groups.append(edges.misoriented)
    chosen = np.concatenate(groups).astype(np.int64)
    if chosen.size == 0:
        return np.zeros(0, dtype=np.int64)
    sizes = edges.counts[chosen].astype(np.int64)
    positions = np.repeat(edges.starts[chosen].astype(np.int64), sizes)
    positions += np.arange(positions.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    return np.unique(edges.side[positions].astype(np.int64) // 3)


def unfixed(after: TopologyReport, steps: tuple[str, ...], required: tuple[str, ...], holes_left: tuple[str, ...],
            shells_left: tuple[str, ...]) -> tuple[str, ...]:
    """Why each required check the output still fails was left."""
    out = []

    def because(reasons, step: str) -> str:
        reasons = list(reasons) or ([f"the {step} step was not asked for"] if step not in steps else [])
        return f" ({'; '.join(reasons[:SHOWN])})" if reasons else ""

    for name in failed_checks(after, required):
        if name == "closed" and after.boundary_edges:
            out.append(f"closed: {after.boundary_edges} boundary edges remain" + because(holes_left, "holes"))
        elif name == "closed":
            # Every edge has two faces or more: what keeps it from being closed is the other checks'.
            kept = [(f"{n} {what} edges", check) for n, what, check in (
                (after.nonmanifold_edges, "non-manifold", "manifold"),
                (after.misoriented_edges, "misoriented", "oriented")) if n]
            out.append(f"closed: no boundary edge remains, but {' and '.join(k for k, _ in kept) or 'some edges'} "
                       f"do (see {' and '.join(c for _, c in kept) or 'manifold and oriented'})")
        elif name == "manifold":
            out.append(f"manifold: {after.nonmanifold_edges} non-manifold edges and {after.nonmanifold_vertices} "
                       "non-manifold vertices remain; repair does not cut or join surfaces (that would change "
                       "the part's shape)")
        elif name == "oriented":
            out.append(f"oriented: {after.misoriented_edges} misoriented edges remain" + because((), "orient"))
        elif name == "outward":
            out.append(f"outward: the signed volume is {after.volume:.10g}" + because(shells_left, "outward"))
        elif name == "no-degenerate":
            out.append(f"no-degenerate: {after.degenerate_faces} degenerate faces remain"
                       + because((), "degenerate"))
        elif name == "no-duplicate":
            out.append(f"no-duplicate: {after.duplicate_faces} duplicate faces remain" + because((), "duplicate"))
        elif name == "no-self-intersection" and after.self_intersections is not None:
            found = after.self_intersections
            example = ""
            if found.samples:
                c = found.samples[0]
                example = f" (e.g. faces {c.faces[0]} and {c.faces[1]}, {c.kind}, at {_point(c.point)})"
            out.append(f"no-self-intersection: {found.count} face pairs cross or overlap{example}; repair moves "
                       "no face, so it cannot part them")
        elif name == "nesting" and after.nesting is not None:
            nesting = after.nesting
            kinds = sorted({kind for _, _, kind in nesting.relations if kind != "inside"})
            counts = f"counted twice {nesting.counted_twice:.6g}, negative {nesting.counted_negative:.6g}"
            out.append(f"nesting: the closed shells do not nest as a solid's ({counts}"
                       + (f"; shells {', '.join(kinds)}" if kinds else "")
                       + "); repair winds shells by their nesting but does not move them")
        else:
            out.append(f"{name}: fails")
    return tuple(out)


def _point(p) -> str:
    return "(" + ", ".join(f"{x:.7g}" for x in p) + ")"
