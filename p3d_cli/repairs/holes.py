"""The ``holes`` step: every boundary loop filled with triangles of its own corners, or left
with the reason.

The boundary sides come from ``p3d check``'s edge grouping (edges used by one face), turned
against their faces and joined into simple loops (``p3d_cli.repairs.loops``); each loop is
triangulated on its own (``p3d_cli.repairs.fill``), never repeating an edge the mesh or an
earlier fill already has. The filled faces are then tested exactly against crossing the faces
near them (``p3d_cli.repairs.solidity``): a hole whose filling would cross another face is left.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from p3d_cli.repairs import solidity
from p3d_cli.repairs.draft import Draft, Grouping
from p3d_cli.repairs.fill import NO_AREA, Hole, fill_hole, fill_triangles
from p3d_cli.repairs.junctions import junction_split
from p3d_cli.repairs.loops import boundary_loops
from p3d_cli.repairs.report import SHOWN, StepReport


@dataclass(frozen=True)
class Holes:
    """What the step found and did.

    Attributes
    ----------
    holes : tuple of (Hole, (k,) int64)
        Every loop, with the faces (draft numbers) around it.
    stray : (s,) int64
        Draft faces of boundary sides on no closed loop.
    nearby : (p, 2) int64 or None
        Each face of a filling with every face found near it when the fillings were tested
        (``p3d_cli.repairs.solidity.crossings_and_near``), in the numbering of the draft the step
        returns (the faces after it are only turned round): a superset of the faces that touch a
        filling face, for the output's self-intersection test (``nearby`` of
        ``p3d_cli.mesh.intersections.self_intersections``). None when no filling was tested, or
        when a face split for a filling refused is whole again (its pairs were found for its
        part).
    """

    holes: tuple[tuple[Hole, np.ndarray], ...]
    stray: np.ndarray
    nearby: np.ndarray | None = None

    @property
    def open_faces(self) -> np.ndarray:
        """Draft faces still on a boundary: around a hole left, or on a stray side."""
        left = [around for hole, around in self.holes if not hole.filled]
        return np.unique(np.concatenate(left + [self.stray])).astype(np.int64)

    def fillings(self, count: int) -> np.ndarray:
        """``(count,)`` int64: for each face of the output (``count`` faces, the fillings last,
        in the holes' order), the hole whose filling on a coordinate plane it belongs to
        (``Hole.projected``), else -1."""
        label = np.full(count, -1, dtype=np.int64)
        position = count - sum(len(hole.triangles) for hole, _ in self.holes if hole.filled)
        for k, (hole, _) in enumerate(self.holes):
            if hole.filled:
                if hole.projected:
                    label[position:position + len(hole.triangles)] = k
                position += len(hole.triangles)
        return label


def boundary_sides(grouping: Grouping, draft: Draft) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Faces, start and end vertices of every boundary side, in the faces' current winding, in
    file order (side ``3 f + k`` of face ``f``): the loops and their fillings are then the same
    whatever numbering the vertex ids and edge groups had."""
    edges, faces = grouping.edges, grouping.faces
    side = np.sort(edges.side[edges.starts[edges.boundary]].astype(np.int64))
    face = side // 3
    slot = side % 3
    u, v = faces[face, slot], faces[face, (slot + 1) % 3]
    turned = draft.flipped[face] != grouping.flipped[face]     # flipped since the grouping
    return face, np.where(turned, v, u), np.where(turned, u, v)


def holes_step(draft: Draft, grouping: Grouping, *, policy: str, flatness: float,
               max_edges: int) -> tuple[Draft, StepReport, Holes]:
    """Fill the holes of ``draft`` (see the module docstring)."""
    if grouping.edges.boundary.size == 0:
        return draft, StepReport("holes", counts={"holes_filled": 0, "holes_left": 0, "faces_added": 0}), \
            Holes((), np.zeros(0, dtype=np.int64))
    face, u, v = boundary_sides(grouping, draft)
    loops, stray = boundary_loops(v, u)              # each side u -> v walked as v -> u
    loops.sort(key=lambda loop: int(face[loop].min()))     # the report lists holes in file order
    has_edge = _EdgeSet(grouping.faces, v, len(draft.points))
    found: list[tuple[Hole, np.ndarray]] = []
    # A loop of three sides fills without asking for the edges (its one triangle's are the
    # loop's): those are filled together, before the others (the same holes).
    three = [i for i, loop in enumerate(loops) if loop.size == 3]
    sides = np.array([loops[i] for i in three], dtype=np.int64).reshape(-1, 3)
    owners = face[sides]
    alike = (owners[:, 0] == owners[:, 1]) & (owners[:, 1] == owners[:, 2])
    lone = set(np.array(three, dtype=np.int64)[alike].tolist())
    filled = [i for i in three if i not in lone]
    early = dict(zip(filled, fill_triangles(draft.points, v[np.array([loops[i] for i in filled], dtype=np.int64)],
                                            policy=policy, flatness=flatness, max_edges=max_edges)))
    for i, loop in enumerate(loops):
        if i in lone:
            # All three sides are one face's: the "hole" is the back of a lone triangle, and
            # filling it would give that face's reverse, enclosing nothing.
            hole = lone_face(draft, v[loop], int(face[loop[0]]))
        else:
            hole = early[i] if i in early else fill_hole(draft.points, v[loop], policy=policy, flatness=flatness,
                                                         max_edges=max_edges, has_edge=has_edge)
            if not hole.filled and hole.reason == NO_AREA:
                hole = _split_junction(draft, hole, face[loop], has_edge)
        if hole.filled:
            has_edge.add(hole.triangles)
            if hole.replaced is not None:
                has_edge.add(hole.replaced[1].reshape(1, 3))
        found.append((hole, face[loop]))
    start = len(draft.faces)
    found, nearby = _refuse_crossings(_applied(draft, found), found, start)
    result = Holes(tuple(found), face[stray], nearby)
    draft = _applied(draft, found)
    return draft, _report(draft, result, start), result


def _applied(draft: Draft, found) -> Draft:
    """The draft with the holes' fillings: split faces replaced, new faces after the others."""
    split = [hole.replaced for hole, _ in found if hole.filled and hole.replaced is not None]
    if split:
        draft = draft.replaced(np.array([f for f, _ in split]), np.array([t for _, t in split]))
    new = [hole.triangles for hole, _ in found if hole.filled]
    return draft.add(np.concatenate(new)) if new else draft


def _split_junction(draft: Draft, hole: Hole, around: np.ndarray, has_edge) -> Hole:
    """A hole of no area closed by splitting the face across its long side, if it is a
    T-junction (``p3d_cli.repairs.junctions``); else the hole as it was."""
    found = junction_split(draft.points, draft.faces, hole.vertices, around, has_edge)
    if found is None:
        return hole
    face, triangles = found
    return dataclasses.replace(hole, triangles=triangles[1:], replaced=(face, triangles[0]), reason=None)


def lone_face(draft: Draft, vertices: np.ndarray, face: int) -> Hole:
    """The outline of a face no other face shares an edge with, left as it is."""
    corners = draft.points[vertices].astype(np.float64)
    centre = tuple(float(x) for x in corners.mean(axis=0))
    size = float((corners.max(axis=0) - corners.min(axis=0)).max())
    origin = int(draft.origin[face])
    where = f"face {origin}" if origin >= 0 else f"new face {face}"
    return Hole(vertices, 3, centre, size, 0.0, None,  # type: ignore[arg-type]
                f"it is the outline of a lone triangle ({where}): filling it would add that face's reverse, "
                "enclosing nothing")


class _EdgeSet:
    """``has_edge(a, b)``: whether the grouped faces, or a fill made so far, have edge ``a b``.

    Only edges between two corners of holes can be asked about (a fill joins a hole's own
    corners), so only those are gathered: one pass over the sides, no sort of them all.
    """

    def __init__(self, faces: np.ndarray, corners: np.ndarray, m: int):
        on_hole = np.zeros(m, dtype=bool)
        on_hole[corners] = True
        a = np.asarray(faces, dtype=np.int64)
        b = np.roll(a, -1, axis=1)
        both = on_hole[a] & on_hole[b]
        lo, hi = np.minimum(a[both], b[both]), np.maximum(a[both], b[both])
        self.m = m
        self.keys: set[int] = set((lo * m + hi).tolist())

    def __call__(self, a: int, b: int) -> bool:
        return min(a, b) * self.m + max(a, b) in self.keys

    def add(self, triangles: np.ndarray) -> None:
        for a, b, c in triangles.tolist():
            for x, y in ((a, b), (b, c), (c, a)):
                self.keys.add(min(x, y) * self.m + max(x, y))


def _refuse_crossings(draft: Draft, found: list, start: int) -> tuple[list, np.ndarray | None]:
    """The holes, with those whose filling crosses or overlaps another face left, and the
    pairs of faces found near the fillings kept (``Holes.nearby``)."""
    if len(draft.faces) == start:
        return found, None
    fillings, projected, position = [], [], start
    for hole, _ in found:
        if hole.filled:
            fillings.append(np.arange(position, position + len(hole.triangles)))
            projected.append(hole.projected)
            position += len(hole.triangles)
    refused, near = solidity.crossings_and_near(draft.points, draft.faces, fillings, projected)
    crossing = iter(refused.tolist())
    out = []
    for hole, around in found:
        if hole.filled and next(crossing):
            hole = dataclasses.replace(hole, triangles=None, reason="its filling would cross other faces",
                                       replaced=None)
        out.append((hole, around))
    return out, _kept_pairs(near, start, fillings, refused, found)


def _kept_pairs(near: np.ndarray, start: int, fillings: list, refused: np.ndarray, found: list) -> np.ndarray | None:
    """The pairs ``near`` (faces of the draft with every filling) renumbered as the draft with
    the fillings kept: the old faces keep their numbers, the kept fillings' follow them in
    order, and the pairs with a refused filling's face are dropped. None when a refused hole
    had split a face (the face is whole again: its pairs were found for its part)."""
    filled = [hole for hole, _ in found if hole.filled]
    if any(gone and hole.replaced is not None for hole, gone in zip(filled, refused.tolist())):
        return None
    number = np.arange(start + sum(len(f) for f in fillings), dtype=np.int64)
    position = start
    for filling, gone in zip(fillings, refused.tolist()):
        if gone:
            number[filling] = -1
        else:
            number[filling] = np.arange(position, position + len(filling))
            position += len(filling)
    pairs = number[near]
    return pairs[(pairs >= 0).all(axis=1)]


def _report(draft: Draft, result: Holes, start: int) -> StepReport:
    places, notes = [], []
    position = start
    for hole, around in result.holes:
        place = {"edges": hole.edges, "centre": list(hole.centre), "size": hole.size, "flatness": hole.flatness,
                 "filled": hole.filled, "faces_around": [int(f) for f in draft.origin[around]]}
        if hole.filled:
            count = len(hole.triangles)
            place["new_faces"] = list(range(position, position + count))
            position += count
            if hole.replaced is not None:
                place["split_face"] = int(draft.origin[hole.replaced[0]])
        else:
            place["reason"] = hole.reason
            notes.append(f"hole of {hole.edges} edges at {_point(hole.centre)} left: {hole.reason}")
        places.append(place)
    if result.stray.size:
        notes.append(f"{result.stray.size} boundary edges do not close into a loop (faces "
                     + ", ".join(str(int(f)) for f in np.unique(draft.origin[result.stray])[:SHOWN]) + "): left")
    filled = sum(1 for hole, _ in result.holes if hole.filled)
    split = sorted(int(draft.origin[hole.replaced[0]]) for hole, _ in result.holes
                   if hole.filled and hole.replaced is not None)
    counts = {"holes_filled": filled, "holes_left": len(result.holes) - filled, "faces_added": position - start,
              "boundary_edges_not_in_loops": int(result.stray.size)}
    if split:
        counts["faces_split"] = len(split)
    return StepReport("holes", counts=counts, faces=tuple(split), new_faces=tuple(range(start, position)),
                      places=tuple(places), notes=tuple(notes))


def _point(p) -> str:
    return "(" + ", ".join(f"{x:.7g}" for x in p) + ")"
