"""Connected components: shells (faces joined across shared edges) and their volumes.

Components are found by a vectorised union-find: each round hooks the larger root of every
still-separate pair onto the smaller (``np.minimum.at``) and then compresses paths by pointer
jumping until every node points at its root. Every component with an unmerged pair merges with
at least one other in a round, so there are O(log n) rounds of O(n + e) work each; in
practice, on meshes in file order, two or three.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.columns import origin_from_bounds
from p3d_cli.mesh.edges import Edges
from p3d_cli.mesh.integrals import MomentSums, triangle_moments
from p3d_cli.mesh.kernels import compiled, takes
from p3d_cli.mesh.report import Shell

#: Shells listed individually (largest first); more are counted but not listed.
LISTED_SHELLS = 100


@dataclass(frozen=True)
class Components:
    labels: np.ndarray  # (n,) int, 0..count-1, numbered by first member
    count: int


def roots(size: int, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The root (smallest node) of every node's component, for edges ``a[i] -- b[i]``."""
    a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
    return chunked_roots(size, lambda: iter([(a, b)]))


def chunked_roots(size: int, arcs) -> np.ndarray:
    """``roots`` for edges given in pieces: ``arcs()`` iterates over ``(a, b)`` int64 pairs of
    arrays, and is called once per round (so the edges are never held whole)."""
    # int64 throughout: numpy gathers with int64 indices about twice as fast as with int32.
    parent = np.arange(size, dtype=np.int64)
    fast = compiled()
    if fast is not None:
        # One compiled union-find pass: its roots are the smallest nodes too, so the same array.
        for a, b in arcs():
            fast.unite(parent, np.ascontiguousarray(a, dtype=np.int64), np.ascontiguousarray(b, dtype=np.int64))
        fast.flatten(parent)
        return parent
    # First round: every node is its own root, so point each node at its smallest
    # neighbour (both ways) without looking roots up; fewer rounds follow than with hooking.
    for a, b in arcs():
        np.minimum.at(parent, a, b)
        np.minimum.at(parent, b, a)
    _jump(parent)
    merged = True
    while merged:
        merged = False
        for a, b in arcs():
            ra, rb = parent[a], parent[b]
            apart = ra != rb
            if apart.any():
                merged = True
                ra, rb = ra[apart], rb[apart]
                np.minimum.at(parent, np.maximum(ra, rb), np.minimum(ra, rb))
        if merged:
            _jump(parent)
    return parent


def _jump(parent: np.ndarray) -> None:
    """Pointer jumping in place until every node points at its root (parents only ever
    decrease, so this ends)."""
    while True:
        jumped = parent[parent]
        if np.array_equal(jumped, parent):
            return
        parent[:] = jumped


def components(size: int, a: np.ndarray, b: np.ndarray) -> Components:
    """Connected components of a graph on ``size`` nodes with edges ``a[i] -- b[i]``.

    Parameters
    ----------
    size : int
    a, b : (e,) int

    Returns
    -------
    Components
        Labels numbered in order of each component's smallest node.
    """
    return _numbered(roots(size, a, b))


def _numbered(parent: np.ndarray) -> Components:
    size = parent.size
    # Roots are the smallest node of their component: numbering them in node order numbers
    # the components by first member, with no sort.
    is_root = parent == np.arange(size, dtype=parent.dtype)
    label_of = np.cumsum(is_root, dtype=np.int32 if size < 2**31 else np.int64) - 1
    return Components(label_of[parent], int(is_root.sum()))


def shells(n: int, edges: Edges) -> Components:
    """Faces joined across shared edges: consecutive sides of each edge group."""
    side, step = edges.side, 1 << 16
    if side.size == 2 * edges.count and (edges.counts == 2).all():   # closed meshes

        def arcs():
            for lo in range(0, side.size, 2 * step):
                pair = side[lo:lo + 2 * step].astype(np.int64) // 3
                yield pair[0::2], pair[1::2]
    else:
        later = np.ones(side.size, dtype=bool)
        later[edges.starts] = False

        def arcs():
            for lo in range(1, side.size, step):
                hi = min(lo + step, side.size)
                keep = later[lo:hi]
                yield (side[lo - 1:hi - 1][keep].astype(np.int64) // 3,
                       side[lo:hi][keep].astype(np.int64) // 3)
    return _numbered(chunked_roots(n, arcs))


def shell_volumes(blocks, n: int, found: Components, volume: float) -> list[Shell]:
    """The ``LISTED_SHELLS`` largest shells with their signed volumes (largest first).

    ``blocks()`` iterates over the triangles again; each listed shell's volume is
    ``triangle_moments`` of its faces in file order.
    """
    if found.count == 0:
        return []
    if found.count == 1:  # the common case: the whole mesh, whose volume is known
        return [Shell(n, 0, volume)]
    sizes = np.bincount(found.labels, minlength=found.count)
    # Labels are numbered by first face, so a stable sort by size keeps ties in file order.
    chosen = np.argsort(-sizes, kind="stable")[:LISTED_SHELLS]
    slot = np.full(found.count, -1, dtype=np.int64)
    slot[chosen] = np.arange(chosen.size)
    first_face = np.full(chosen.size, -1, dtype=np.int64)
    parts: list[list[np.ndarray]] = [[] for _ in chosen]
    done = 0
    for block in blocks():
        block = np.asarray(block)
        where = slot[found.labels[done:done + len(block)]]
        listed = np.flatnonzero(where >= 0)
        if listed.size:
            order = np.argsort(where[listed], kind="stable")
            listed = listed[order]
            bounds = np.flatnonzero(np.diff(where[listed])) + 1
            for group in np.split(listed, bounds):
                k = int(where[group[0]])
                parts[k].append(block[group])
                if first_face[k] < 0:
                    first_face[k] = done + int(group[0])
        done += len(block)
    out = []
    for k, label in enumerate(chosen.tolist()):
        faces = np.concatenate(parts[k]) if len(parts[k]) > 1 else parts[k][0]
        out.append(Shell(int(sizes[label]), int(first_face[k]), _volume(faces)))
    return out


def _volume(faces: np.ndarray, block: int = 65536) -> float:
    """``triangle_moments(faces).volume``, by the compiled kernels when built: the same
    origin (the bounds' centre) and the same blocks, summed with the same bits
    (``p3d_cli.mesh.kernels``). An axis whose two bounds are both ±0 goes to numpy: the
    centre's sign is then that of numpy's min and max (a zero bound beside a nonzero one
    leaves the centre's bits alone); so does a block the kernels do not read."""
    fast = compiled()
    if fast is None or not takes(faces) or not faces.size:
        return float(triangle_moments(faces).volume)
    box, finite = fast.bounds(faces)
    box = np.array(box)
    if not finite or ((box[:3] == 0) & (box[3:] == 0)).any():
        return float(triangle_moments(faces).volume)
    sums = MomentSums(origin_from_bounds(box[:3], box[3:], faces.dtype == np.float32))
    for start in range(0, len(faces), block):
        part = faces[start:start + block]
        _, _, totals, magnitude, weighted, _ = fast.block(part, *sums.origin, None, 0)
        sums.add_sums(np.array(totals), magnitude, np.array(weighted), len(part))
    return float(sums.moments().volume)
