"""The steps that mend faces one by one: ``weld``, ``degenerate`` and ``duplicate``.

- ``weld`` merges vertices closer than a tolerance (``p3d check``'s weld: transitive, each group
  taking the coordinates of one of its vertices, so no new coordinate is made); the faces whose
  corners moved are the ones it changed.
- ``degenerate`` removes faces of exactly zero area, decided as ``p3d check`` decides them
  (``p3d_cli.mesh.faces.zero_area_faces``: collinear or repeated corners, exactly).
- ``duplicate`` removes each face with the same three vertices as an earlier face (in any order
  or winding), keeping the earlier one, as ``p3d check`` counts them
  (``p3d_cli.mesh.faces.duplicate_faces``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.edges import Edges
from p3d_cli.mesh.faces import duplicate_candidates, duplicate_faces, repeated_vertex_faces, zero_area_faces
from p3d_cli.repair import solidity
from p3d_cli.repair.draft import Draft
from p3d_cli.repair.report import StepReport

#: Faces per block when testing for zero area (bounded temporaries).
_BLOCK = 1 << 14


def weld_step(draft: Draft, tolerance: float) -> tuple[Draft, StepReport]:
    """Merge vertices closer than ``tolerance`` (see the module docstring)."""
    try:
        target, weld = solidity.weld_points(draft.points.astype(np.float64), tolerance)
    except solidity.Unavailable:
        return draft, StepReport("weld", ran=False, notes=(
            "not done: this build of p3d lacks the weld of p3d check (p3d_cli.mesh.weld)",))
    target = np.asarray(target, dtype=np.int64)
    welded = draft.renamed(target)
    moved = np.flatnonzero(welded.moved & ~draft.moved)
    merged = np.flatnonzero(target != np.arange(target.size))
    places = tuple({"point": [float(x) for x in draft.points[v]],
                    "merged_into": [float(x) for x in draft.points[int(target[v])]]}
                   for v in merged.tolist())
    return welded, StepReport(
        "weld", counts={"vertices_merged": int(merged.size), "faces_moved": int(moved.size),
                        "tolerance": float(tolerance), "largest_distance": float(weld.largest_distance)},
        faces=tuple(int(f) for f in draft.origin[moved]), places=places)


def degenerate_step(draft: Draft) -> tuple[Draft, StepReport]:
    """Remove the faces of exactly zero area."""
    zero = []
    for lo in range(0, len(draft.faces), _BLOCK):
        block = draft.points[draft.faces[lo:lo + _BLOCK]]
        zero.append(zero_area_faces(columns(block)) + lo)
    gone = np.concatenate(zero) if zero else np.zeros(0, dtype=np.int64)
    keep = np.ones(len(draft.faces), dtype=bool)
    keep[gone] = False
    return draft.keep(keep), StepReport("degenerate", counts={"faces_removed": int(gone.size)},
                                        faces=tuple(int(f) for f in draft.origin[gone]))


def duplicate_step(draft: Draft, edges: Edges) -> tuple[Draft, StepReport]:
    """Remove every face that repeats an earlier one (``edges``: the draft's grouping, which
    narrows the faces to compare as ``p3d check`` narrows them)."""
    faces = draft.faces
    repeated = repeated_vertex_faces(faces)
    candidates = duplicate_candidates(len(faces), edges.side, edges.starts, edges.counts, repeated)
    pairs = duplicate_faces(faces, candidates)
    keep = np.ones(len(faces), dtype=bool)
    keep[pairs[:, 1]] = False
    places = tuple({"face": int(draft.origin[b]), "repeats": int(draft.origin[a])} for a, b in pairs.tolist())
    return draft.keep(keep), StepReport("duplicate", counts={"faces_removed": int(pairs.shape[0])},
                                        faces=tuple(int(f) for f in draft.origin[pairs[:, 1]]), places=places)

