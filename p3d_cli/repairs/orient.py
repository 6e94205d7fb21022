"""Orientation: each shell wound one way (the ``orient`` step), then outward (``outward``).

**Consistent.** Two faces sharing an edge that no other face uses agree when they traverse it
in opposite directions. Faces joined across such edges form a *patch* (a shell of ``p3d
check`` with its non-manifold edges cut). A patch can be wound consistently exactly when every
cycle of faces in it crosses an even number of disagreeing edges (it is not a Möbius strip or
a Klein bottle): then it has two consistent windings, each face keeping or swapping its own.

Both are found at once on the *double cover*: every face ``f`` becomes two nodes, ``(f, kept)``
and ``(f, flipped)``, and an agreeing edge joins ``(a, kept)`` with ``(b, kept)`` (and flipped
with flipped), a disagreeing one ``(a, kept)`` with ``(b, flipped)``. Connected components of the
cover (the union-find of ``p3d_cli.mesh.shells``) are then the consistent windings: a patch
whose two nodes of one face fall in one component cannot be wound consistently; otherwise the
component holding its first face kept is one winding, the other component the other. Of the
two, the step keeps the one that flips fewer faces (the first face's, on a tie), so a face is
only flipped when an edge says it disagrees with most of its patch.

**Outward.** A closed patch (no boundary or non-manifold edge) encloses a region; its signed
volume is positive when it is wound outward. A solid's shells are outward where the region
inside them is solid and inward around a cavity: a shell inside an odd number of others is a
cavity. The step flips whole patches only, to that parity, with the nesting decided exactly
(``p3d_cli.repairs.solidity``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.edges import Edges
from p3d_cli.mesh.shells import _numbered, chunked_roots, shells
from p3d_cli.repairs import solidity
from p3d_cli.repairs.draft import Draft
from p3d_cli.repairs.report import StepReport

#: Sides per arc chunk of the union-find.
_STEP = 1 << 16


@dataclass(frozen=True)
class Patches:
    """The patches of a draft and the winding that makes each consistent.

    Attributes
    ----------
    labels : (k,) int
        Patch of every face, numbered by first face.
    count : int
    flip : (k,) bool
        Faces to flip so that every orientable patch is consistent (the fewer of each patch).
    nonorientable : (p,) int64
        Patches that no winding makes consistent (left as they are).
    """

    labels: np.ndarray
    count: int
    flip: np.ndarray
    nonorientable: np.ndarray


def pair_groups(edges: Edges) -> tuple[np.ndarray, np.ndarray]:
    """The two sides of every edge used by exactly two faces."""
    two = np.flatnonzero(edges.counts == 2)
    start = edges.starts[two].astype(np.int64)
    return edges.side[start].astype(np.int64), edges.side[start + 1].astype(np.int64)


def disagreeing(edges: Edges) -> np.ndarray:
    """Whether the two sides of each edge of ``pair_groups`` run the same way (disagree)."""
    start = edges.starts[np.flatnonzero(edges.counts == 2)].astype(np.int64)
    return edges.forward[start] == edges.forward[start + 1]


def patches(face_count: int, edges: Edges, one_shell: bool = False) -> Patches:
    """Patches and their consistent windings (see the module docstring); ``one_shell``: the
    faces are known to form one shell of ``p3d check`` (no union-find needed without a
    misoriented or non-manifold edge)."""
    if edges.misoriented.size == 0 and edges.nonmanifold.size == 0 and one_shell:
        none = np.zeros(face_count, dtype=bool)
        return Patches(np.zeros(face_count, dtype=np.int64), 1, none, np.zeros(0, dtype=np.int64))
    if edges.misoriented.size == 0:
        # Every patch is consistent already: its components, on the faces alone (without a
        # non-manifold edge they are ``p3d check``'s shells, found by its own code).
        found = shells(face_count, edges) if edges.nonmanifold.size == 0 else _pair_components(face_count, edges)
        none = np.zeros(face_count, dtype=bool)
        return Patches(found.labels, found.count, none, np.zeros(0, dtype=np.int64))
    first, second = pair_groups(edges)
    a, b = first // 3, second // 3
    flipped = disagreeing(edges).astype(np.int64)

    def arcs():
        for lo in range(0, a.size, _STEP):
            fa, fb, s = a[lo:lo + _STEP], b[lo:lo + _STEP], flipped[lo:lo + _STEP]
            yield 2 * fa, 2 * fb + s
            yield 2 * fa + 1, 2 * fb + 1 - s

    root = chunked_roots(2 * face_count, arcs)
    kept, turned = root[0::2], root[1::2]
    # A patch's smallest node is its first face kept: the component holding it is the winding
    # of the first face, and a face lies in it kept or flipped.
    relative = kept > turned
    base = np.minimum(kept, turned) // 2
    found = _numbered(base)
    labels, count = found.labels, found.count
    flips = np.bincount(labels, weights=relative, minlength=count)
    sizes = np.bincount(labels, minlength=count)
    bad = np.zeros(count, dtype=bool)
    bad[labels[kept == turned]] = True
    keep_first = flips * 2 <= sizes          # the first face's winding flips fewer (or as many)
    flip = np.where(keep_first[labels], relative, ~relative) & ~bad[labels]
    return Patches(labels, count, flip, np.flatnonzero(bad).astype(np.int64))


def _pair_components(face_count: int, edges: Edges):
    """Faces joined across the edges exactly two faces use."""
    first, second = pair_groups(edges)
    a, b = first // 3, second // 3

    def arcs():
        for lo in range(0, a.size, _STEP):
            yield a[lo:lo + _STEP], b[lo:lo + _STEP]

    return _numbered(chunked_roots(face_count, arcs))


def patch_volumes(triangles: np.ndarray, labels: np.ndarray, count: int) -> np.ndarray:
    """Signed volume of every patch of ``triangles`` ``(k, 3, 3)``: tetrahedra from the patch's
    own first corner (so a patch far from the origin keeps its digits), in float64."""
    origin = np.zeros((count, 3))
    origin[labels[::-1]] = triangles[::-1, 0]
    total = np.zeros(count)
    for lo in range(0, len(triangles), _STEP):
        block, lab = triangles[lo:lo + _STEP].astype(np.float64), labels[lo:lo + _STEP]
        o = origin[0] if count == 1 else origin[lab]
        a, b, c = (block[:, k] - o for k in range(3))
        b -= a
        c -= a
        det = a[:, 0] * (b[:, 1] * c[:, 2] - b[:, 2] * c[:, 1]) + a[:, 1] * (b[:, 2] * c[:, 0] - b[:, 0] * c[:, 2]) \
            + a[:, 2] * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
        total += det.sum() if count == 1 else np.bincount(lab, weights=det, minlength=count)
    return total / 6.0


def orient_step(draft: Draft, found: Patches) -> tuple[Draft, StepReport]:
    """Flip the faces that disagree with most of their patch."""
    notes = nonorientable_notes(draft, found)
    if not found.flip.any():
        return draft, StepReport("orient", counts={"faces_flipped": 0, "shells": 0}, notes=notes)
    flipped = np.flatnonzero(found.flip)
    touched = np.unique(found.labels[flipped])
    places = tuple({"shell_first_face": first_origin(draft, found.labels, p),
                    "faces_flipped": int(np.count_nonzero(found.flip & (found.labels == p)))}
                   for p in touched.tolist())
    return draft.flip(found.flip), StepReport(
        "orient", counts={"faces_flipped": int(flipped.size), "shells": int(touched.size)},
        faces=tuple(draft.origin[flipped].tolist()), places=places, notes=notes)


def nonorientable_notes(draft: Draft, found: Patches) -> tuple[str, ...]:
    return tuple(f"the shell from face {first_origin(draft, found.labels, p)} cannot be wound consistently "
                 "(a Moebius strip or a Klein bottle): left as it was" for p in found.nonorientable.tolist())


def first_origin(draft: Draft, labels: np.ndarray, patch: int) -> int:
    """The number of a patch's first face: in the input, or in the output for a face added."""
    f = int(np.flatnonzero(labels == patch)[0])
    return int(draft.origin[f]) if draft.origin[f] >= 0 else f


def joined(found: Patches, holes) -> Patches:
    """``found`` with the faces added by filled holes (after the others, hole by hole): each takes
    the patch of the faces around its hole, and patches one hole touches become one."""
    parent = list(range(found.count))

    def root(p: int) -> int:
        while parent[p] != p:
            parent[p] = parent[parent[p]]
            p = parent[p]
        return p

    extra: list[int] = []
    for hole, around in holes:
        if hole.filled:
            own = sorted({root(int(p)) for p in found.labels[around].tolist()})
            for p in own[1:]:
                parent[p] = own[0]
            extra += [own[0]] * len(hole.triangles)
    merged = np.array([root(p) for p in range(found.count)], dtype=np.int64)
    labels = np.concatenate([merged[found.labels], merged[np.array(extra, dtype=np.int64)]])
    return Patches(labels, found.count, np.zeros(labels.size, dtype=bool), merged[found.nonorientable])


def outward_step(draft: Draft, triangles: np.ndarray, found: Patches,
                 open_patches: np.ndarray) -> tuple[Draft, StepReport, np.ndarray]:
    """Flip every closed patch whose winding does not match its nesting (outward at even
    depth, a cavity at odd); ``open_patches`` take no part. ``triangles`` are the draft's
    faces as triangles (``Draft.output_triangles``). Returns the draft, the report and the
    faces flipped."""
    labels, count = found.labels, found.count
    closed = np.ones(count, dtype=bool)
    closed[open_patches] = False
    closed[found.nonorientable] = False
    present = np.zeros(count, dtype=bool)
    present[labels] = True                 # patches merged into another have no face of their own
    closed &= present
    volume = patch_volumes(triangles, labels, count)
    flat = np.flatnonzero(closed & (volume == 0))
    closed = np.flatnonzero(closed & (volume != 0))
    notes = [f"the shell from face {first_origin(draft, labels, p)} encloses no volume: its outward side is "
             "undefined; left as it was" for p in flat.tolist()]
    open_count = int(np.count_nonzero(present)) - closed.size - flat.size
    if open_count:
        pieces = "piece" if open_count == 1 else "pieces"
        notes.append(f"{open_count} open {pieces} of surface (bounded by a hole left or a non-manifold edge, or "
                     "without a consistent winding): outward is undefined for an open surface; left as "
                     f"{'they were' if open_count != 1 else 'it was'}")
    depth = solidity.nesting_depths(draft.points, draft.faces, labels, count, closed)
    wrong = [p for p in closed.tolist() if (volume[p] > 0) != (depth[p] % 2 == 0)]
    flip = np.isin(labels, np.array(wrong, dtype=np.int64))
    flipped = np.flatnonzero(flip)
    origin = draft.origin[flipped]
    places = tuple({"shell_first_face": first_origin(draft, labels, p), "faces": int(np.count_nonzero(labels == p)),
                    "signed_volume_before": float(volume[p]), "cavity": bool(depth[p] % 2)} for p in wrong)
    report = StepReport(
        "outward", counts={"shells_flipped": len(wrong), "faces_flipped": int(flipped.size),
                           "closed_shells": int(closed.size), "cavities": sum(depth[p] % 2 for p in closed.tolist())},
        faces=tuple(origin[origin >= 0].tolist()), new_faces=tuple(flipped[origin < 0].tolist()), places=places,
        notes=tuple(notes))
    return (draft.flip(flip) if flipped.size else draft), report, flipped
