"""What repair takes from ``p3d check``'s exact solidity tests, in the steps' vocabulary.

- ``weld_points``: ``p3d check --weld``'s grouping of near vertices (``p3d_cli.mesh.weld``);
- ``nesting_depths``: how many closed shells lie around each closed shell, by exact winding
  numbers (``p3d_cli.mesh.nesting``), for the ``outward`` step (a shell inside an odd number of
  others is a cavity);
- ``crossing_fillings``: the fillings of holes with a face whose interior crosses or overlaps
  another face (``p3d_cli.mesh.intersections``, on the faces near the fillings only): a filled
  hole must add no self-intersection; ``crossings_and_near`` gives as well the faces found near
  each filling face, with which the output's own test pairs the fillings.

The modules are imported where they are used: a repair that needs none of them does not load
the self-intersection machinery.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np


def weld_points(points: np.ndarray, tolerance: float):
    """``(target, weld)``: for every point ``(m, 3)`` the smallest index of the points it is
    merged with (transitively, closer than ``tolerance``), and what was merged."""
    from p3d_cli.mesh.weld import weld_points as groups

    return groups(points, tolerance)


def nesting_depths(points: np.ndarray, faces: np.ndarray, labels: np.ndarray, count: int,
                   closed: np.ndarray) -> dict[int, int]:
    """How many closed shells lie around each closed shell, decided exactly, as ``p3d check``
    nests them: two closed shells whose faces cross (``p3d_cli.mesh.intersections``, run on
    the faces of the closed shells whose boxes meet another's) are neither inside the other.

    Parameters
    ----------
    points : (m, 3)
        Coordinates by vertex id (one id per distinct point).
    faces : (k, 3) int
    labels : (k,) int
        Shell of every face, ``0..count-1``.
    closed : (s,) int
        The closed shells (the others take no part): no edge of theirs has more than two faces
        (the repair steps' closed patches: a face on such an edge makes its patch open).

    Returns
    -------
    dict
        ``{shell: depth}`` for every closed shell (0: in no other).
    """
    closed = np.asarray(closed, dtype=np.int64)
    if closed.size <= 1:
        return {int(s): 0 for s in closed}
    from p3d_cli.mesh.intersections import self_intersections
    from p3d_cli.mesh.layout import Layout
    from p3d_cli.mesh.nesting import boxed_together, shell_boxes, shell_nesting
    from p3d_cli.mesh.shells import Components

    faces = np.asarray(faces)
    points = np.asarray(points, dtype=np.float64)
    others = np.setdiff1d(np.arange(count), closed)
    layout = Layout(faces.ravel(), len(points), Components(np.asarray(labels), count), np.zeros(0, dtype=np.int64),
                    np.zeros((0, 2), dtype=np.int64), others)
    # Without the crossings, a shell with one corner inside a crossing one would be nested in
    # it (and turned as a cavity, or its parent found the smaller of the two). Only shells whose
    # boxes meet can cross: the test takes their faces alone (none, for parts side by side).
    labels = np.asarray(labels)
    lo, hi = shell_boxes(points, faces, labels, count)
    members = np.flatnonzero(np.isin(labels, boxed_together(lo, hi, closed)))
    # Their faces' pairs within one shell are not asked (``patches``: a shell's own crossings
    # nest nothing), and no edge of a closed shell has more than two faces (such a face makes
    # its patch open), so there are no crowded edges to look for.
    crossing = np.zeros((0, 2), dtype=np.int64)
    if members.size:
        among = self_intersections(points, faces[members], nonmanifold_edges=np.zeros((0, 2), dtype=np.int64),
                                   patches=labels[members])
        crossing = members[among.pairs]
    found = shell_nesting(points, faces, layout, crossing, boxes=(lo, hi))
    depth: dict[int, int] = {}
    for shell in closed.tolist():
        d, outer = 0, found.parent.get(shell)
        while outer is not None:
            d += 1
            outer = found.parent.get(outer)
        depth[shell] = d
    return depth


#: Fillings of at least this many faces are first screened pair by pair (below); a smaller
#: one (the many one-face holes of a damaged file) goes straight to the whole test.
SCREENED = 16
#: Faces of a screened filling touching old faces along lines, probed first (below).
PROBES = 8


def crossing_fillings(points: np.ndarray, faces: np.ndarray, fillings: Sequence[np.ndarray],
                      projected: Sequence[bool] | None = None) -> np.ndarray:
    """Which fillings (each an array of face ids into ``faces``) have a face whose interior
    crosses or overlaps another face: ``(len(fillings),)`` bool, decided exactly
    (``crossings_and_near``, without the pairs)."""
    return crossings_and_near(points, faces, fillings, projected)[0]


def crossings_and_near(points: np.ndarray, faces: np.ndarray, fillings: Sequence[np.ndarray],
                       projected: Sequence[bool] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Which fillings (each an array of face ids into ``faces``) have a face whose interior
    crosses or overlaps another face: ``(len(fillings),)`` bool, decided exactly.

    ``projected[k]`` says that filling ``k`` is a triangulation of its loop seen exactly on a
    plane (``p3d_cli.repairs.fill.Hole.projected``): its triangles' shadows on that plane meet
    only in shared edges and corners, and each triangle lies over its shadow one to one, so
    two of them meet only in the edges and corners they share, which the pair test finds
    ``NONE``. Their pairs are left out of the tests below (``patches`` of
    ``self_intersections``); a fan of ``k`` slivers has ``k²/2`` of them, nearly all of the
    pairs its tests would take.

    A filling is refused when ``p3d check``'s self-intersection test of the whole mesh
    (``p3d_cli.mesh.intersections``) would report a pair with one of its faces. The test is run
    on fewer faces, with the same answer:

    1. Every new face is paired with the faces whose boxes meet its triangle
       (``p3d_cli.repairs.near``), a superset of the faces that touch it.
    2. A filling of ``SCREENED`` faces or more is screened first: its faces' pairs with old,
       non-degenerate faces go through the exact pair test (``triangle_pairs.classify``); a pair
       that crosses or overlaps is one that the whole test reports (those kinds are final there),
       so such a filling is refused at once. Where faces only touch along lines (the contact
       pairs), the first ``PROBES`` faces of the filling that do are tested with every face
       that touches them (their pairs of step 1, and the whole filling) by the whole test: the
       pairs with those faces are the whole mesh's, so one found refuses the filling. A hole too
       large for its rim (a flat disc through the far side of a tube) is so refused on a few
       of its faces, where the lines of contact of all of them cost the most of the test.
    3. The fillings left are tested with the faces paired with them (step 1) by the whole
       self-intersection test (``self_intersections``). Every face that touches one of their
       faces is there, so the pairs with their faces, and the lines of contact along them, are
       those of the whole mesh.

    Returns
    -------
    crossing : (len(fillings),) bool
    near : (p, 2) int64
        The pairs of step 1: each face of a filling with every face (of another filling, or
        old) whose box meets its triangle, a superset of the faces that touch it (the
        ``nearby`` of ``self_intersections``, for a later test of the same faces).
    """
    sizes = np.array([len(f) for f in fillings], dtype=np.int64)
    crossing = np.zeros(len(sizes), dtype=bool)
    if sizes.sum() == 0:
        return crossing, np.zeros((0, 2), dtype=np.int64)
    from p3d_cli.geometry.predicates import in_safe_range
    from p3d_cli.mesh.intersections import self_intersections, zero_area_faces
    from p3d_cli.mesh.triangle_pairs import CONTACT, CROSSING, OVERLAP, classify
    from p3d_cli.repairs.near import near_pairs

    points = np.asarray(points, dtype=np.float64)
    faces = np.asarray(faces)
    new = np.concatenate([np.asarray(f, dtype=np.int64) for f in fillings])
    owner = np.repeat(np.arange(len(sizes)), sizes)
    group = np.full(len(faces), -1, dtype=np.int64)
    group[new] = owner
    on_plane = np.zeros(len(sizes), dtype=bool) if projected is None else np.asarray(projected, dtype=bool)
    patches = np.full(len(faces), -1, dtype=np.int64)
    patches[new] = np.where(on_plane[owner], owner, -1)
    at, near = near_pairs(points, faces, new, group)
    screened = (sizes >= SCREENED)[owner[at]] & (group[near] < 0)
    if screened.any():
        i, j = new[at[screened]], near[screened]
        safe = in_safe_range(points)
        others = np.unique(j)
        flat = others[zero_area_faces(points, faces[others], safe)]
        live = ~np.isin(j, flat)
        kind, _ = classify(points, faces, i[live], j[live], safe)
        crossing[owner[at[screened][live][(kind == CROSSING) | (kind == OVERLAP)]]] = True
        touching = i[live][kind == CONTACT]
        probes = touching[~crossing[group[touching]]]
        if probes.size:
            crossing |= _probed(points, faces, new, owner, group, at, near, probes, patches)
    left = ~crossing[owner]
    if left.any():
        chosen = np.union1d(new[left], near[left[at]])
        found = self_intersections(*_compact(points, faces[chosen]), patches=patches[chosen],
                                   nearby=_within(chosen, new[at], near))
        if len(found.pairs):
            hit = chosen[found.pairs.ravel()]
            crossing[group[hit[group[hit] >= 0]]] = True
    return crossing, np.stack([new[at], near], axis=1)


def _probed(points: np.ndarray, faces: np.ndarray, new: np.ndarray, owner: np.ndarray, group: np.ndarray,
            at: np.ndarray, near: np.ndarray, touching: np.ndarray, patches: np.ndarray) -> np.ndarray:
    """The fillings refused by the whole self-intersection test of their first ``PROBES``
    faces in ``touching`` (face ids, in order), with every face that touches those (the pairs
    within a filling of ``patches`` left out)."""
    from p3d_cli.mesh.intersections import self_intersections

    labels = group[touching]
    probes = np.concatenate([np.unique(touching[labels == g])[:PROBES] for g in np.unique(labels)])
    refused = np.zeros(int(owner.max()) + 1, dtype=bool)
    probed = np.zeros(len(faces), dtype=bool)
    probed[probes] = True
    whole = np.isin(group[new], np.unique(labels))
    chosen = np.union1d(new[whole], near[probed[new[at]]])
    found = self_intersections(*_compact(points, faces[chosen]), patches=patches[chosen],
                               nearby=_within(chosen, new[at], near))
    if len(found.pairs):
        hit = chosen[found.pairs.ravel()]
        refused[group[hit[probed[hit]]]] = True
    return refused


def _within(chosen: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The pairs ``(a[k], b[k])`` of faces both in ``chosen`` (ascending face ids), as
    positions in it: ``(p, 2)`` int64."""
    i = np.minimum(np.searchsorted(chosen, a), len(chosen) - 1)
    j = np.minimum(np.searchsorted(chosen, b), len(chosen) - 1)
    both = (chosen[i] == a) & (chosen[j] == b)
    return np.stack([i[both], j[both]], axis=1)


def _compact(points: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The points the faces use and the faces renumbered onto them: the self-intersection
    test's passes over the points (their box, the fans' certificates) then cost what the few
    faces do, not the whole mesh, with the same exact answers by face."""
    used, faces = np.unique(faces, return_inverse=True)
    return points[used], faces.reshape(-1, 3)
