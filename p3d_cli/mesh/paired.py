"""``p3d check``'s fast path for a soup whose sides pair up: one sort of edge keys, no vertex sort.

The usual input of ``p3d check`` is a clean closed mesh. For it, one sort of packed *edge*
keys (as ``p3d props`` sorts, ``p3d_cli.mesh.closed``) gives everything at once:

1. **Pass 1** (``p3d_cli.mesh.paired_keys``) reads the blocks once: bounds, finite check,
   exact zero-area faces, the signed volume (the same blocks about the same origin as
   ``vertices.group_corners``, so the same bits) and, for every side ``3 f + k``, the key
   ``(edge hash high bits) | direction | side``.
2. **One in-place sort.** When every key group is two sides running opposite ways, each side
   has a twin, and ``pi(c) = next(twin(c))`` is a permutation of the corners whose cycles are
   the fans around the vertices (``p3d_cli.mesh.fans``). Two colliding edges make a balanced
   group of four or more: those few sides are paired by their exact end points (one more
   pass over the file for them only). Anything else (a boundary, non-manifold or misoriented
   edge, a side whose ends hash alike) leaves the fast path: the general one decides. Most
   such meshes leave before the sort: the edge keys of sides used once each way cancel in
   ``sum(forward keys) - sum(backward keys)`` (mod 2^64), so a sum that does not cancel
   proves the mesh is not clean, at the cost of two sums per block.
3. **Fans**: the compiled kernels walk each cycle once; numpy's pointer doubling
   (``label = min(label, label[q]); q = q[q]``) labels each cycle with its smallest corner in
   ``log2(valence)`` rounds. Each fan's first corner (file order) is its representative, and
   fans are numbered in file order, so later work reads memory nearly in order (the hash
   order of a corner sort reads it at random, which costs more than the arithmetic).
4. **Pass 2** compares every corner's coordinates with its fan representative's, exactly: it
   proves that every twin really shares its two end points, whatever the hashes did (a
   difference leaves the fast path). Fans at the same point are then found by sorting the
   representatives' hashes (a sixth of the corners) and comparing coordinates exactly; each
   such point is one vertex with several fans, a non-manifold vertex.
5. **Shells** by union-find over the fans (each face joins its three: a fan's faces are
   joined across its edges), which numbers them by first face with no sort.

**Boundary edges** (``boundary=True``: ``p3d check``, and ``p3d repair``, which reads the
boundary sides found: ``edges.lone_sides``). A mesh with holes does not balance, so pass 1 does
not stop there. After the sort a key group of one side is a *boundary side* (no other side has
its exact edge: equal edges have equal keys), ``pi = -1`` there, and the fans round the
boundary's vertices are open chains instead of cycles (``fan_chains`` walks each from its
start; numpy joins ``c`` and ``pi[c]`` by union-find). Groups that are neither one side nor one
each way (colliding keys, or a misoriented or non-manifold edge) are sorted out by their sides'
exact end points; any exact edge used otherwise than once each way or once sends the mesh to
the general path, and pass 2 proves every twin as before. A vertex with several chains or
cycles (two holes meeting at a point) is a non-manifold vertex, as the general path counts it.

The results are those of the general path (``topology``): the tests compare both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.closed import corner_hashes
from p3d_cli.mesh.edges import corner_slot
from p3d_cli.mesh.kernels import NotTaken, compiled, confirm_fans, sort
from p3d_cli.mesh.paired_exact import exact_edges, exact_twins
from p3d_cli.mesh.paired_keys import keyed_pass
from p3d_cli.mesh.shells import Components, _numbered, chunked_roots, roots
from p3d_cli.mesh.vertices import CHUNK
from p3d_cli.mesh.volume import SignedVolume

#: Offsets from corner ``3 f + k`` to the next corner of face ``f``, by ``k``.
_NEXT = np.array([1, 1, -2], dtype=np.int64)


@dataclass
class Paired:
    """What the fast path found for a soup whose every edge is used once each way.

    Attributes
    ----------
    ids : (3n,) int32 or int64
        Exact vertex id of each corner (not contiguous: a vertex of several fans takes the
        id of its first fan).
    vertices : int
        Number of distinct points.
    nonmanifold : (k,) int
        Ids of the vertices with more than one fan, in the general path's vertex order
        (full corner hash, then coordinates).
    zero_area : (z,) int64
        Faces of exactly zero area, ascending.
    volume : float
        The local sums' volume; NaN when there are boundary sides (whose exact term the
        caller adds to ``sums``, as the general path does).
    shells : Components
    boundary : (b,) int64
        The boundary sides (each the one use of its edge), ascending; empty when closed.
    sums : SignedVolume
        The signed volume's sums, about the general path's origin.
    """

    ids: np.ndarray
    vertices: int
    nonmanifold: np.ndarray
    zero_area: np.ndarray
    volume: float
    shells: Components
    boundary: np.ndarray
    sums: SignedVolume


def paired_topology(blocks, n: int, where: str | None = None, hasher=None,
                    boundary: bool = False) -> Paired | None:
    """The fast path's findings, or None when some edge is not used exactly once each way
    (with ``boundary``: once each way, or once).

    Parameters
    ----------
    blocks : callable
        Returns an iterator over ``(k, 3, 3)`` float arrays in file order (read twice, or
        three times when edge keys collide).
    n : int
        Number of triangles (at least one).
    where : str, optional
        The input's name: when given, a NaN or infinite coordinate raises ``InputError``.
    hasher : callable, optional
        ``hasher(cols) -> (3, k) uint64`` corner hashes (default ``closed.corner_hashes``'):
        any function gives the same results, which lets the tests force collisions.
    boundary : bool
        Also take a soup whose edges are used once each way or once (boundary edges): its
        fans around the boundary's vertices are open chains (``Paired.boundary``).
    """
    bits = max(int(3 * n - 1).bit_length(), 1)
    first = keyed_pass(blocks, n, bits, where, hasher, balanced=not boundary)
    if first is None:
        return None
    keys, presorted, zero, sums = first
    del first                           # memory: the keys go as soon as they are read
    if not presorted:
        sort(keys)  # radix, when compiled: the same order
    pi = _orbit_map(keys, bits, blocks, boundary)
    del keys
    if pi is None:
        return None
    lone = np.flatnonzero(pi < 0) if boundary else np.zeros(0, dtype=np.int64)
    fan, count, is_first = _fan_ids(pi) if lone.size == 0 else _chain_ids(pi)   # in pi's buffer
    del pi
    points = _confirm(blocks, fan, count, is_first)
    del is_first
    if points is None:
        return None
    ids, vertices, nonmanifold = _merge_fans(fan, count, points)
    return Paired(ids, vertices, nonmanifold, zero, sums.volume() if lone.size == 0 else math.nan,
                  _shells(fan, count), lone.astype(np.int64), sums)


def _orbit_map(keys: np.ndarray, bits: int, blocks, boundary: bool = False):
    """``pi[c] = next(twin(c))`` from the sorted side keys, or None when some key group is
    not one side each way (after pairing the sides of colliding groups exactly). With
    ``boundary``, a side whose exact edge no other side uses is a boundary side: ``pi = -1``."""
    pi = np.empty(keys.size, dtype=np.int32 if keys.size < 2**31 else np.int64)
    if boundary:
        fast = compiled()
        if fast is None or not keys.flags.c_contiguous:
            return _orbit_map_grouped(keys, bits, blocks, pi, boundary)
        _, other = fast.open_pairs(keys, bits, pi)
        # The sides of other groups, marked -2: by their exact end points (the numpy road's
        # ``_open_orbit_map`` does the same with the same sides).
        return pi if other == 0 else _link_exactly(blocks, pi, np.flatnonzero(pi == -2))
    mask, shift, one = np.uint64((1 << bits) - 1), np.uint64(bits), np.uint64(1)
    pairs = keys.reshape(-1, 2) if keys.size % 2 == 0 else None
    step = CHUNK
    clean = pairs is not None
    fast = compiled()
    if clean and fast is not None and keys.flags.c_contiguous:
        clean = fast.pairs(keys, bits, pi)          # the loop below, in one compiled pass
    elif clean:
        for lo in range(0, len(pairs), step):
            a, b = pairs[lo:lo + step, 0], pairs[lo:lo + step, 1]
            # One edge per pair, direction 0 then 1: the keys agree above the direction bit
            # and differ in it (sorted, ``a`` has the 0); a third use of an edge would break
            # the pairing of the next pair.
            if not (((a ^ b) >> shift) == one).all():
                clean = False
                break
            _link(pi, (a & mask).astype(np.int64), (b & mask).astype(np.int64))
    if not clean:
        return _orbit_map_grouped(keys, bits, blocks, pi)
    return pi


def _link(pi: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
    """Record twin sides ``a[i]``, ``b[i]``: ``pi[a] = next(b)`` and ``pi[b] = next(a)``."""
    pi[a] = b + _NEXT[corner_slot(b)]
    pi[b] = a + _NEXT[corner_slot(a)]


def _orbit_map_grouped(keys: np.ndarray, bits: int, blocks, pi: np.ndarray, boundary: bool = False):
    """``_orbit_map`` when the keys do not simply pair up: group them, pair the two-side
    groups, and the sides of balanced groups of four or more (colliding hashes) exactly."""
    if boundary:
        return _open_orbit_map(keys, bits, blocks, pi)
    mask = np.uint64((1 << bits) - 1)
    starts, counts, forward = _key_groups(keys, bits)
    if ((counts % 2 == 1) | (2 * forward != counts)).any():
        return None                     # an edge not used once each way, whatever the hash
    two = starts[counts == 2]
    _link(pi, (keys[two] & mask).astype(np.int64), (keys[two + 1] & mask).astype(np.int64))
    crowded = np.flatnonzero(counts > 2)
    sizes = counts[crowded]
    offsets = np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    sides = (keys[np.repeat(starts[crowded], sizes) + offsets] & mask).astype(np.int64)
    twins = exact_twins(blocks, sides)
    if twins is None:
        return None
    _link(pi, *twins)
    return pi


def _key_groups(keys: np.ndarray, bits: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The groups of sorted side keys with one edge hash: each group's first position, its
    number of sides and how many of them run forward."""
    edge = keys >> np.uint64(bits + 1)
    new = np.ones(edge.size, dtype=bool)
    np.not_equal(edge[1:], edge[:-1], out=new[1:])
    starts = np.flatnonzero(new)
    del edge, new
    counts = np.diff(np.append(starts, keys.size))
    forward = np.add.reduceat(((keys >> np.uint64(bits)) & np.uint64(1)).astype(np.int64), starts)
    return starts, counts, forward


def _open_orbit_map(keys: np.ndarray, bits: int, blocks, pi: np.ndarray):
    """``_orbit_map_grouped`` with boundary sides: a group of one side is a boundary side; a
    group of two sides running opposite ways, a pair; every other group (two sides the same
    way, three or more: colliding hashes, or a misoriented or non-manifold edge) is sorted out
    by the exact end points of its sides, where each exact edge must be used once each way or
    once (None otherwise)."""
    mask = np.uint64((1 << bits) - 1)
    starts, counts, forward = _key_groups(keys, bits)
    pi[(keys[starts[counts == 1]] & mask).astype(np.int64)] = -1
    two = starts[(counts == 2) & (forward == 1)]
    _link(pi, (keys[two] & mask).astype(np.int64), (keys[two + 1] & mask).astype(np.int64))
    hard = np.flatnonzero((counts > 2) | ((counts == 2) & (forward != 1)))
    if hard.size == 0:
        return pi
    sizes = counts[hard]
    offsets = np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    return _link_exactly(blocks, pi, (keys[np.repeat(starts[hard], sizes) + offsets] & mask).astype(np.int64))


def _link_exactly(blocks, pi: np.ndarray, sides: np.ndarray):
    """Twin or boundary the given sides (whole key groups) by their exact end points; None
    when some exact edge among them is used otherwise than once each way or once."""
    found = exact_edges(blocks, sides)
    if found is None:
        return None
    a, b, lone = found
    _link(pi, a, b)
    pi[lone] = -1
    return pi


def _chain_ids(pi: np.ndarray):
    """``_fan_ids`` where ``pi`` is -1 at the boundary sides: the fans around the boundary's
    vertices are open chains. The compiled kernels walk each chain or cycle once
    (``fan_chains``); numpy joins ``c`` and ``pi[c]`` by union-find. Same numbers as
    ``_fan_ids``: by smallest corner, into pi's buffer."""
    first = np.empty(pi.size, dtype=bool)
    fast = compiled()
    if fast is not None and pi.flags.c_contiguous and pi.flags.writeable:
        count = fast.fan_chains(pi, first)
        return pi, count, first
    linked = np.flatnonzero(pi >= 0)
    parent = roots(pi.size, linked, pi[linked])
    first = parent == np.arange(pi.size)
    number = np.cumsum(first, dtype=pi.dtype)
    number -= 1
    pi[:] = number[parent]
    return pi, int(number[-1]) + 1, first


def _fan_ids(pi: np.ndarray):
    """Fan number of every corner (the cycles of ``pi``, numbered in file order), the number
    of fans, and the mask of each fan's first corner.

    Pointer doubling: ``label[c]`` is the smallest corner among the first ``w`` of its cycle
    from ``c``, ``w`` being 3 at the start (``c``, ``pi[c]``, ``pi[pi[c]]``: no lookup of labels
    needed) and doubling each round; every cycle is covered when adjacent corners agree
    (window minima of a cycle longer than the window differ where the window leaves its
    smallest corner). Valence 6 or less, most vertices of most meshes, takes one round.

    The compiled kernels walk each cycle once instead (``fan_cycles``), in ascending order of
    its smallest corner: the same numbers, written into ``pi``'s buffer as here.
    """
    fast = compiled()
    if fast is not None and pi.flags.c_contiguous and pi.flags.writeable:
        first = np.empty(pi.size, dtype=bool)
        count = fast.fan_cycles(pi, first)
        return pi, count, first
    label = np.arange(pi.size, dtype=pi.dtype)
    np.minimum(label, pi, out=label)
    jump = _gather(pi, pi)
    np.minimum(label, jump, out=label)
    jump, looked = _gather(pi, jump), jump  # pi applied 3 times: the window's length
    while True:
        np.minimum(label, _gather(label, jump, looked), out=label)
        if np.array_equal(label, _gather(label, pi, looked)):
            break
        jump, looked = _gather(jump, jump, looked), jump
    del jump, looked
    first = label == np.arange(pi.size, dtype=pi.dtype)
    number = np.cumsum(first, dtype=pi.dtype)
    number -= 1
    count = int(number[-1]) + 1
    # The fan numbers go into pi's buffer, which is not needed any more (memory).
    return _gather(number, label, pi), count, first


def _gather(source: np.ndarray, index: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``source[index]`` into ``out`` (not ``source`` nor ``index``), in slices: numpy widens
    int32 indices to a whole int64 copy first, which would double the memory of a lookup."""
    if out is None:
        out = np.empty(index.size, dtype=source.dtype)
    for lo in range(0, index.size, 4 * CHUNK):
        # Valid indices: mode="clip" only spares the copy of ``out`` the default mode makes.
        np.take(source, index[lo:lo + 4 * CHUNK], out=out[lo:lo + 4 * CHUNK], mode="clip")
    return out


def _confirm(blocks, fan: np.ndarray, count: int, is_first: np.ndarray):
    """Pass 2: every corner against its fan's first corner, exactly. Returns the fans'
    coordinates ``(count, 3)`` (the input's dtype), or None when some corner differs."""
    fast = compiled()
    if fast is not None:
        try:
            return confirm_fans(blocks, fan, count, is_first)
        except NotTaken:
            pass
    axes = None
    done = 0
    for block in blocks():
        # Compared as stored (float32 or float64; equal exactly when the widened values
        # are, and -0.0 == 0.0): no widening copy.
        block = np.asarray(block)
        k = len(block)
        if k == 0:
            continue
        if axes is None:
            axes = np.zeros((3, count), dtype=block.dtype)
        corners = np.ascontiguousarray(block).reshape(3 * k, 3)     # corner 3 f + k order
        vid = fan[3 * done:3 * (done + k)]
        # A fan's first corner is its earliest: in this block or before. So set the block's
        # first corners first, then compare every corner.
        own = is_first[3 * done:3 * (done + k)]
        firsts = vid[own]
        for axis in range(3):
            axes[axis, firsts] = corners[own, axis]
        differ = axes[0, vid] != corners[:, 0]
        differ |= axes[1, vid] != corners[:, 1]
        differ |= axes[2, vid] != corners[:, 2]
        if differ.any():
            return None                             # colliding keys paired two edges
        done += k
    assert axes is not None
    return np.ascontiguousarray(axes.T)


def _merge_fans(fan: np.ndarray, count: int, points: np.ndarray):
    """Exact vertex ids from the fans: fans at one point are one vertex (several fans: a
    non-manifold vertex). Returns ``(ids, vertices, nonmanifold)`` (see ``Paired``)."""
    hashes = corner_hashes(points)
    # Fans whose hashes agree (the compiled radix sort, when there is one): a few, by chance,
    # besides those that share a point, whose hashes are equal.
    ordered = hashes.copy()
    sort(ordered)
    shared = ordered[1:][ordered[1:] == ordered[:-1]]
    del ordered
    if shared.size == 0:                # the usual case: one fan per point
        return fan, count, np.zeros(0, dtype=np.int64)
    candidates = np.flatnonzero(np.isin(hashes, shared))
    coords = points[candidates].astype(np.float64) + 0.0
    h = hashes[candidates]
    # The general path's vertex order: full hash, then coordinates (vertices.py).
    order = np.lexsort((candidates, coords[:, 2], coords[:, 1], coords[:, 0], h))
    candidates, coords, h = candidates[order], coords[order], h[order]
    new = np.ones(candidates.size, dtype=bool)
    new[1:] = (h[1:] != h[:-1]) | (coords[1:] != coords[:-1]).any(axis=1)
    group = np.cumsum(new) - 1
    starts = np.flatnonzero(new)
    sizes = np.diff(np.append(starts, candidates.size))
    if (sizes == 1).all():
        return fan, count, np.zeros(0, dtype=np.int64)      # hash collisions only
    # Each point takes the id of its first fan (the candidates are ascending within a point).
    rep = np.arange(count, dtype=fan.dtype)
    rep[candidates] = candidates[starts][group]
    ids = rep[fan]
    return ids, count - int((sizes - 1).sum()), candidates[starts[sizes > 1]].astype(np.int64)


def _shells(fan: np.ndarray, count: int) -> Components:
    """Faces joined across edges: a fan's faces are joined across its edges, so the shells
    are the components of the fans, each face joining its three."""
    faces = fan.reshape(-1, 3)
    step = CHUNK

    def arcs():
        for lo in range(0, len(faces), step):
            part = faces[lo:lo + step].astype(np.int64)
            yield part[:, 0], part[:, 1]
            yield part[:, 1], part[:, 2]

    # Fans are numbered by first corner, so the smallest fan of a shell is one of its first
    # face's: the fans' components, numbered by smallest fan, are numbered by first face.
    of_fan = _numbered(chunked_roots(count, arcs))
    return Components(of_fan.labels[faces[:, 0]], of_fan.count)
