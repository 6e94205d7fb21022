"""How a mesh's closed shells lie in each other, and what that does to its volume.

The divergence theorem integrates the winding number ``w`` of the surface: every point counts
``w`` times. A solid's surface has ``w = 1`` inside and ``0`` outside (``-1`` and ``0`` wound
inward, which ``p3d check`` reports as ``outward``). Separate closed shells do that when each
one inside another is wound opposite to it (a cavity in a body, a body in that cavity, ...):
a hollow part. A shell inside another wound the same way (two exports of one body, a body
inside another) puts ``w = 2`` in it: its volume is counted twice. Shells that cross (their
faces intersect, ``p3d_cli.mesh.intersections``) count their common region twice too, and
that region's volume is bounded by the smaller shell's.

For every pair of closed shells whose bounding boxes nest, one vertex of the inner candidate
(not on the other's surface) is tested against the outer with an exact winding number
(``p3d_cli.mesh.rays``). Shells that do not cross are either apart or nested, so one point
decides. From the nesting, the winding number of every region follows, and so the volume
counted twice (or counted negative: a cavity outside every body), exactly up to the float
sums of the shells' volumes.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.predicates import in_safe_range
from p3d_cli.mesh.broadphase import box_pairs, outward_boxes
from p3d_cli.mesh.layout import Layout
from p3d_cli.mesh.rays import winding_number
from p3d_cli.mesh.solidity_report import Nesting, ShellPlace

#: Shells listed in the report (largest first); the rest are counted.
LISTED = 100
#: Vertices of an inner candidate tried before the pair is called coincident.
_TRIES = 16


def shell_nesting(points: np.ndarray, faces: np.ndarray, layout: Layout, crossing_pairs: np.ndarray,
                  volume_of_one: float | None = None, boxes: tuple | None = None) -> Nesting:
    """The nesting of the closed shells of a mesh.

    Parameters
    ----------
    points : (m, 3) float64
        Vertex coordinates by id.
    faces : (n, 3) int
        Vertex ids of every face.
    layout : Layout
        The shells and which of them are open.
    crossing_pairs : (k, 2) int
        Face pairs that cross or overlap (``SelfIntersections.pairs``).
    volume_of_one : float, optional
        The mesh's signed volume, used as its shell's when it has one (no sum over the faces).
    boxes : (lo, hi), optional
        ``shell_boxes`` of these shells, when the caller has them.
    """
    labels = layout.shells.labels
    count = layout.shells.count
    closed = np.ones(count, dtype=bool)
    closed[layout.open_shells] = False
    if count == 1 and volume_of_one is not None and np.isfinite(volume_of_one) and volume_of_one != 0:
        volume = np.array([float(volume_of_one)])
        scaled = volume
    else:
        # Signs and comparisons from volumes of the points scaled by a power of two (no
        # overflow for parts at 1e300, no underflow at 1e-300); what is reported is rescaled.
        scaled, power = _shell_volumes(points, faces, labels, count, closed)
        volume = np.ldexp(scaled, power)
    closed &= scaled != 0                       # a flat shell encloses nothing
    ids = np.flatnonzero(closed)
    sizes = np.bincount(labels, minlength=count)
    if count == 1:
        first = np.zeros(1, dtype=np.int64)
    else:
        first = np.full(count, len(faces), dtype=np.int64)
        np.minimum.at(first, labels, np.arange(len(faces)))
    relations: dict[tuple[int, int], str] = {}
    for a, b in _crossing_shells(labels, crossing_pairs, closed):
        relations[(a, b)] = "crossing"
    parent = {int(s): None for s in ids}
    if boxes is None and ids.size > 1:
        boxes = shell_boxes(points, faces, labels, count)
    lo, hi = boxes if ids.size > 1 else (None, None)
    if ids.size > 1:
        _nest(points, faces, labels, ids, scaled, relations, parent, lo, hi)
        _cut_cycles(parent, scaled)
    counts = _windings(parent, scaled)
    winding = {s: counts[s] for s in sorted(ids.tolist(), key=lambda s: -abs(scaled[s]))}   # outer first
    twice, negative = _miscounted(volume, parent, winding)
    bound = 0.0
    for (a, b), kind in relations.items():
        if kind == "crossing" and np.sign(scaled[a]) == np.sign(scaled[b]):
            # Their common region lies in both shells and in both boxes.
            common = float(np.prod(np.clip(np.minimum(hi[a], hi[b]) - np.maximum(lo[a], lo[b]), 0, None)))
            bound += min(abs(float(volume[a])), abs(float(volume[b])), common)
    listed = sorted(ids.tolist(), key=lambda s: (-sizes[s], s))[:LISTED]
    places = tuple(ShellPlace(s, int(sizes[s]), int(first[s]), float(volume[s]), parent[s], winding[s])
                   for s in listed)
    ordered = tuple(sorted((a, b, kind) for (a, b), kind in relations.items()))
    return Nesting(places, int(ids.size), ordered, float(twice), float(negative), float(bound), parent,
                   {int(s): float(volume[s]) for s in ids})


def _shell_volumes(points, faces, labels, count, closed) -> tuple[np.ndarray, int]:
    """Signed volume of every closed shell (``closed``: ``(count,)`` bool; 0 for the others,
    which nothing reads), as ``(v, k)`` with the volume ``v · 2**k``: signed tetrahedra from the
    shell's own first vertex (the sums are local to each shell, so a part far from the origin
    keeps its digits), the points scaled by a power of two to a span near 1 (exact, and no
    product over- or underflows). The open shells' faces are left out of each block; a shell's
    own terms are summed in the same order (one by one, block by block) either way."""
    span = float(np.abs(points).max()) if len(points) else 0.0
    shift = -int(np.frexp(span)[1]) if 0 < span < np.inf else 0
    points = np.ldexp(points, shift)
    first_vertex = np.zeros((count, 3))
    first_vertex[labels[::-1]] = points[faces[::-1, 0]]
    volume = np.zeros(count)
    for start in range(0, len(faces), 1 << 16):
        f, lab = faces[start:start + (1 << 16)], labels[start:start + (1 << 16)]
        wanted = closed[lab]
        if not wanted.all():
            f, lab = f[wanted], lab[wanted]
        o = first_vertex[lab]
        a, b, c = (points[f[:, k]] - o for k in range(3))
        det = np.einsum("ij,ij->i", a, np.cross(b, c))
        volume += np.bincount(lab, weights=det, minlength=count)
    return volume / 6.0, -3 * shift


def _crossing_shells(labels, pairs, closed) -> set[tuple[int, int]]:
    if len(pairs) == 0:
        return set()
    a, b = labels[pairs[:, 0]], labels[pairs[:, 1]]
    keep = (a != b) & closed[a] & closed[b]
    return {(int(min(x, y)), int(max(x, y))) for x, y in zip(a[keep], b[keep])}


def boxed_together(lo: np.ndarray, hi: np.ndarray, shells: np.ndarray) -> np.ndarray:
    """Those of ``shells`` whose bounding box (``shell_boxes``) meets another's of them,
    ascending: the only ones that can cross or lie inside one of the others."""
    shells = np.asarray(shells, dtype=np.int64)
    if shells.size < 2:
        return np.zeros(0, dtype=np.int64)
    lo32, hi32 = outward_boxes(lo[shells], hi[shells])
    met = np.zeros(shells.size, dtype=bool)
    for i, j in box_pairs(lo32, hi32):
        met[i] = True
        met[j] = True
    return shells[met]


def shell_boxes(points, faces, labels, count):
    """Bounding boxes ``(count, 3)`` of every shell. A shell's faces mostly come in runs (a
    file lists a part's faces together): each run of one label is reduced at once, and only
    the runs' boxes are scattered (``ufunc.at`` per face took 0.4 s a million faces)."""
    lo = np.full((count, 3), np.inf)
    hi = np.full((count, 3), -np.inf)
    for start in range(0, len(faces), 1 << 16):
        corners = points[faces[start:start + (1 << 16)]]
        lab = labels[start:start + (1 << 16)]
        runs = np.flatnonzero(np.concatenate([[True], lab[1:] != lab[:-1]]))
        np.minimum.at(lo, lab[runs], np.minimum.reduceat(corners.min(axis=1), runs, axis=0))
        np.maximum.at(hi, lab[runs], np.maximum.reduceat(corners.max(axis=1), runs, axis=0))
    return lo, hi


def _nest(points, faces, labels, ids, volume, relations, parent, lo, hi) -> None:
    """Test every pair of closed shells whose boxes nest, and record the smallest shell around
    each one (``parent``)."""
    count = len(lo)
    lo32, hi32 = outward_boxes(lo[ids], hi[ids])
    safe = in_safe_range(points)
    order = np.argsort(labels, kind="stable")
    starts = np.searchsorted(labels[order], np.arange(count + 1))

    def shell_faces(s):
        members = order[starts[s]:starts[s + 1]]

        def blocks():
            for k in range(0, members.size, 1 << 16):
                yield points[faces[members[k:k + (1 << 16)]]]
        return blocks

    for i, j in box_pairs(lo32, hi32):
        for a, b in zip(ids[i].tolist(), ids[j].tolist()):
            key = (min(a, b), max(a, b))
            if key in relations:
                continue
            for inner, outer in ((a, b), (b, a)):
                if not ((lo[outer] <= lo[inner]).all() and (hi[inner] <= hi[outer]).all()):
                    continue
                found = _inside(points, faces, order, starts, inner, shell_faces(outer), safe)
                if found is None:
                    relations[(inner, outer)] = "coincident"
                elif found != 0:
                    relations[(inner, outer)] = "inside"
                    if parent[inner] is None or abs(volume[outer]) < abs(volume[parent[inner]]):
                        parent[inner] = outer
                    break


def _cut_cycles(parent: dict, volume: np.ndarray) -> None:
    """Make ``parent`` a forest. Shells that cross may each hold a point of the other (the
    crossing pairs, when known, keep such pairs from being tested), so the links can close a
    cycle: in each, the shell of the largest volume keeps no parent (the smallest id on a tie)."""
    done: set = set()
    for s in parent:
        path: list = []
        on_path: set = set()
        t = s
        while t is not None and t not in done and t not in on_path:
            path.append(t)
            on_path.add(t)
            t = parent[t]
        if t is not None and t in on_path:
            cycle = path[path.index(t):]
            parent[max(cycle, key=lambda c: (abs(float(volume[c])), -c))] = None
        done.update(path)


def _windings(parent: dict, volume: np.ndarray) -> dict:
    """The winding number of the region just inside each shell: its own volume's sign plus its
    parent's winding. Walked up the parents (a shell around a crossing one can be the smaller:
    the volumes do not order them)."""
    winding: dict = {}
    for s in parent:
        chain = []
        t = s
        while t is not None and t not in winding:
            chain.append(t)
            t = parent[t]
        base = winding[t] if t is not None else 0
        for c in reversed(chain):
            base += int(np.sign(volume[c]))
            winding[c] = base
    return winding


def _inside(points, faces, order, starts, inner, outer_faces, safe) -> int | None:
    """The winding number about shell ``outer`` of a point of shell ``inner``'s surface: a
    vertex, or the midpoint of an edge (exact in floats), that does not lie on the outer
    surface (None when every point tried does)."""
    members = order[starts[inner]:starts[inner + 1]][:_TRIES]
    corners = points[faces[members]]
    tries = [points[v] for v in np.unique(faces[members].ravel())[:_TRIES]]
    tries += [(corners[k, i] + corners[k, (i + 1) % 3]) / 2 for k in range(len(members)) for i in range(3)]
    for p in tries:
        w = winding_number(p, outer_faces, safe)
        if w is not None:
            return w
    return None


def _miscounted(volume, parent, winding) -> tuple[float, float]:
    """Volume counted twice or more, and counted negative, region by region: the region just
    inside shell ``s`` and outside the shells directly inside it has winding ``winding[s]``."""
    children: dict[int, float] = {}
    for s, outer in parent.items():
        if outer is not None:
            children[outer] = children.get(outer, 0.0) + abs(float(volume[s]))
    total = sum(float(volume[s]) for s in parent)
    sign = 1 if total >= 0 else -1
    twice = negative = 0.0
    for s, w in winding.items():
        region = abs(float(volume[s])) - children.get(s, 0.0)
        if sign * w >= 2:
            twice += (sign * w - 1) * region
        elif sign * w < 0:
            negative += -sign * w * region
    return twice, negative
