"""The steps that mend faces one by one: ``weld``, ``degenerate`` and ``duplicate``.

- ``weld`` merges vertices closer than a tolerance (``p3d check``'s weld: transitive), each
  group taking the coordinates of the vertex most corners use (so no new coordinate is made,
  and the fewest faces move); the faces whose corners moved are the ones it changed.
- ``degenerate`` removes faces of exactly zero area, decided as ``p3d check`` decides them
  (``p3d_cli.mesh.faces.zero_area_faces``: collinear or repeated corners, exactly).
- ``duplicate`` removes each face with the same three vertices as an earlier face (in any order
  or winding), keeping the earlier one, as ``p3d check`` counts them
  (``p3d_cli.mesh.faces.duplicate_faces``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.faces import duplicate_candidates, duplicate_faces, repeated_vertex_faces, zero_area_faces
from p3d_cli.repairs import solidity
from p3d_cli.repairs.draft import Draft, draft_edges
from p3d_cli.repairs.report import StepReport

#: Faces per block when testing for zero area (bounded temporaries).
_BLOCK = 1 << 14


def weld_step(draft: Draft, tolerance: float) -> tuple[Draft, StepReport]:
    """Merge vertices closer than ``tolerance`` (see the module docstring)."""
    groups, _ = solidity.weld_points(draft.points.astype(np.float64), tolerance)
    target = _most_used(np.asarray(groups, dtype=np.int64), draft.faces)
    welded = draft.renamed(target)
    moved = np.flatnonzero(welded.moved & ~draft.moved)
    merged = np.flatnonzero(target != np.arange(target.size))
    wide = draft.points.astype(np.float64)
    largest = float(np.sqrt(((wide[merged] - wide[target[merged]]) ** 2).sum(axis=1)).max()) if merged.size else 0.0
    places = tuple({"point": [float(x) for x in draft.points[v]],
                    "merged_into": [float(x) for x in draft.points[int(target[v])]]}
                   for v in merged.tolist())
    return welded, StepReport(
        "weld", counts={"vertices_merged": int(merged.size), "faces_moved": int(moved.size),
                        "tolerance": float(tolerance), "largest_distance": largest},
        faces=tuple(draft.origin[moved].tolist()), places=places)


def _most_used(group: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Each vertex's new id: of the vertices welded into one group, the one the most corners
    use (the first used in the file on a tie), so that the fewest faces move."""
    m = group.size
    uses = np.bincount(faces.ravel(), minlength=m)
    first = np.full(m, faces.size, dtype=np.int64)
    np.minimum.at(first, faces.ravel(), np.arange(faces.size))
    order = np.lexsort((first, -uses, group))
    leader = np.empty(m, dtype=np.int64)
    starts = np.flatnonzero(np.r_[True, group[order][1:] != group[order][:-1]])
    leader[group[order][starts]] = order[starts]
    return leader[group]


def degenerate_step(draft: Draft, known: np.ndarray | None = None) -> tuple[Draft, StepReport]:
    """Remove the faces of exactly zero area (``known``: those ``p3d check``'s topology found,
    while the draft's faces are the input's)."""
    if known is not None:
        gone = np.asarray(known, dtype=np.int64)
    else:
        zero = []
        for lo in range(0, len(draft.faces), _BLOCK):
            block = draft.points[draft.faces[lo:lo + _BLOCK]]
            zero.append(zero_area_faces(columns(block)) + lo)
        gone = np.concatenate(zero) if zero else np.zeros(0, dtype=np.int64)
    if gone.size == len(draft.faces):
        return draft, StepReport("degenerate", counts={"faces_removed": 0}, notes=(
            f"every face ({gone.size}) has zero area: removing them would leave nothing; left as they were",))
    keep = np.ones(len(draft.faces), dtype=bool)
    keep[gone] = False
    return draft.keep(keep), StepReport("degenerate", counts={"faces_removed": int(gone.size)},
                                        faces=tuple(draft.origin[gone].tolist()))


def duplicate_step(draft: Draft, known: np.ndarray | None = None) -> tuple[Draft, StepReport]:
    """Remove every face that repeats an earlier one. ``known``: the ``(first, later)`` pairs
    of *input* faces ``p3d check``'s topology found (while no face has moved), else the pairs are
    found on the draft's own edges, narrowed as ``check`` narrows them."""
    faces = draft.faces
    if known is not None:
        # Input numbers to draft rows; a pair one of whose faces is gone (degenerate: then both
        # are) is no pair any more.
        rows = np.searchsorted(draft.origin, known)
        rows = np.minimum(rows, max(len(draft.origin) - 1, 0))
        present = (draft.origin[rows] == known).all(axis=1) if len(draft.origin) else np.zeros(len(known), bool)
        pairs = rows[present]
    else:
        edges = draft_edges(faces)
        repeated = repeated_vertex_faces(faces)
        candidates = duplicate_candidates(len(faces), edges.side, edges.starts, edges.counts, repeated)
        pairs = duplicate_faces(faces, candidates)
    keep = np.ones(len(faces), dtype=bool)
    keep[pairs[:, 1]] = False
    places = tuple({"face": int(draft.origin[b]), "repeats": int(draft.origin[a])} for a, b in pairs.tolist())
    return draft.keep(keep), StepReport("duplicate", counts={"faces_removed": int(pairs.shape[0])},
                                        faces=tuple(draft.origin[pairs[:, 1]].tolist()), places=places)

