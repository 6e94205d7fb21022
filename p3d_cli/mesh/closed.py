"""Is a triangle soup closed? Edge matching by exact vertex coordinates, in one sort.

"Closed" means every edge is shared by exactly two faces that traverse it in opposite
directions, vertices being matched by their exact coordinates (no tolerance, no welding;
``-0.0`` equals ``0.0``). This needs no vertex merging: each corner's coordinates are hashed
to 64 bits, each directed edge to a key whose high 63 bits identify the undirected edge and
whose low bit gives its direction; the mesh is closed when, after one sort, the keys pair up as
(direction 0, direction 1) with no third use. A hash collision could only make a closed mesh
look open (never the reverse, barring a second, matching collision), so a "not closed" verdict
is confirmed: a key used once, twice the same way, an odd number of times or unevenly in the
two directions proves an exact edge that is not used once each way (equal edges have equal
keys); only balanced groups of four or more sides, which two colliding closed edges would make,
have their end points compared exactly
(``doubtful_edges``, ``sides_pair_up_exactly``). An open mesh costs one more pass over its
sorted keys, not a vertex merge.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.kernels import compiled, sort
from p3d_cli.mesh.splitmix import mix

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


_ONE = np.uint64(1)
_MAX = np.uint64(0xFFFFFFFFFFFFFFFF)


def corner_hashes(triangles: np.ndarray) -> np.ndarray:
    """64-bit hashes of each corner's exact coordinates.

    Parameters
    ----------
    triangles : (n, 3, 3) float32 or float64

    Returns
    -------
    (n, 3) uint64
    """
    # Widen, and add 0.0 so that -0.0 and 0.0 (equal coordinates) hash alike.
    coords = np.asarray(triangles, dtype=np.float64) + 0.0
    bits = coords.view(np.uint64)
    h = mix(bits[..., 0] ^ _GOLDEN)
    h ^= bits[..., 1]
    h = mix(h)
    h ^= bits[..., 2]
    return mix(h)


def _column_hashes(columns: np.ndarray, scratch: np.ndarray) -> np.ndarray:
    """``corner_hashes`` of triangles given as ``(3, 3, n)`` columns, as ``(3, n)`` (slot, face)."""
    n = columns.shape[2]
    # Same hash as corner_hashes: mix(mix(mix(x ^ G) ^ y) ^ z) of the float64 bits, after
    # adding 0.0 so that -0.0 and 0.0 hash alike.
    coord = np.empty((3, n))
    h = np.add(columns[:, 0], 0.0, out=coord).view(np.uint64).copy()
    h ^= _GOLDEN
    mix(h, scratch)
    h ^= np.add(columns[:, 1], 0.0, out=coord).view(np.uint64)
    mix(h, scratch)
    h ^= np.add(columns[:, 2], 0.0, out=coord).view(np.uint64)
    mix(h, scratch)
    return h


def _side_keys(h: np.ndarray, scratch: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Directed edge keys of the sides 0→1, 1→2, 2→0 given ``(3, n)`` corner hashes.

    Returns the keys ``(3, n)`` flattened (sides whose ends hash alike left out: they bound
    nothing) and the mask of kept sides (None when every side is kept).
    """
    start, end = h, h[[1, 2, 0]]            # edges 0→1, 1→2, 2→0 of every triangle
    keep = None
    if (start == end).any():                # rare: a degenerate edge bounds nothing
        keep = start != end
        start, end = start[keep], end[keep]
        scratch = np.empty_like(start)
    forward = start < end
    key = np.minimum(start, end)
    high = np.maximum(start, end, out=end)
    key *= _GOLDEN
    key += high
    mix(key, scratch)
    key &= ~_ONE
    key |= forward
    return key.reshape(-1), keep


def side_keys(columns: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """``_side_keys`` of triangles given as ``(3, 3, n)`` columns: the keys of the sides with
    two distinct ends, in (slot, face) order, and the mask of those sides (None when all
    are). The compiled kernels make the same keys in one pass when built."""
    kernels = compiled()
    n = columns.shape[2]
    if kernels is None:
        scratch = np.empty((3, n), dtype=np.uint64)
        return _side_keys(_column_hashes(columns, scratch), scratch)
    keys = np.empty(3 * n, dtype=np.uint64)
    keep = np.empty((3, n), dtype=bool)
    if kernels.side_keys(columns.transpose(2, 0, 1), keys, keep.view(np.uint8)):
        return keys[keep.reshape(-1)], keep
    return keys, None


def column_edge_keys(columns: np.ndarray) -> np.ndarray:
    """Keys of the directed edges (0→1, 1→2, 2→0) of triangles given as columns.

    Bit 0 of a key is the direction (1 when the edge runs from the smaller corner hash to the
    larger), the other bits identify the undirected edge; sides whose two ends are the same
    point are left out (they bound nothing). Computed with reused buffers from the layout the
    one-pass analysis already holds.

    Parameters
    ----------
    columns : (3, 3, n) float64
        Vertex slot, axis, triangle; exact world coordinates (not shifted).

    Returns
    -------
    (m,) uint64
    """
    scratch = np.empty((3, columns.shape[2]), dtype=np.uint64)
    return _side_keys(_column_hashes(columns, scratch), scratch)[0]


def keys_pair_up(keys: np.ndarray, presorted: bool = False) -> bool:
    """True when the sorted keys come in (direction 0, direction 1) pairs of one edge each.

    Sorts ``keys`` in place (unless ``presorted``: they are sorted already).
    """
    if not presorted:
        sort(keys)
    if keys.size == 0 or keys.size % 2:
        return False
    pairs = keys.reshape(-1, 2)
    # Each pair must be (2e, 2e + 1): one edge, direction 0 then 1. That also rules out a third
    # use of an edge: sorted, the next pair starts at or above 2e + 1, and being even, above it.
    # Checked in slices so that the temporaries stay small beside the keys (peak memory).
    step = 1 << 18
    for start in range(0, len(pairs), step):
        first, second = pairs[start:start + step, 0], pairs[start:start + step, 1]
        if (first & _ONE).any() or not np.array_equal(first + _ONE, second):
            return False
    return True


def doubtful_edges(keys: np.ndarray) -> np.ndarray:
    """The edge keys (direction bit cleared) that may still pair up exactly, in sorted ``keys``
    that ``keys_pair_up`` rejected; empty when the mesh is certainly open.

    Equal edges have equal keys, so all the sides of one exact edge share a key group. A key
    group of 1, 2 or an odd number of sides, or with unequal numbers of the two directions,
    therefore holds an exact edge that is not used exactly once each way: the mesh is open
    whatever the hash did. Only a group of 4, 6, ... balanced sides can be two or more
    closed edges whose 64-bit keys collided; those need the exact test.
    """
    kernels = compiled()
    if kernels is not None and keys.flags.c_contiguous:
        doubtful = kernels.groups(keys)[3]
        return keys[:0] if doubtful is None else np.frombuffer(doubtful, dtype=np.uint64).copy()
    found = []
    for edge, counts, forward in key_groups(keys):
        bad = ~((counts == 2) & (forward == 1))
        if ((counts[bad] < 4) | (2 * forward[bad] != counts[bad])).any():
            return keys[:0]                 # proven open: the usual case, found early
        found.append(edge[bad])
    return np.concatenate(found) if found else keys[:0]


def key_groups(keys: np.ndarray):
    """The key groups of sorted side ``keys`` (a group: the keys ``2e`` and ``2e + 1`` of one
    edge key ``e``), a slice of whole groups at a time, so that the temporaries stay small
    beside the keys (peak memory, and page faults: this is on every open mesh's road).

    Yields
    ------
    edge : (g,) uint64
        Each group's edge key.
    counts : (g,) int64
        Its number of sides.
    forward : (g,) int32
        How many of them run in direction 1.
    """
    step, start = 1 << 18, 0
    while start < keys.size:
        stop = min(start + step, keys.size)
        last = keys[stop - 1] | _ONE
        if stop < keys.size and last != _MAX:
            stop = int(np.searchsorted(keys, last + _ONE))
        elif stop < keys.size:
            stop = keys.size
        part = keys[start:stop]
        edge = part >> _ONE
        starts = np.flatnonzero(np.concatenate(([True], edge[1:] != edge[:-1])))
        counts = np.diff(np.append(starts, part.size))
        forward = np.add.reduceat((part & _ONE).astype(np.int32), starts)
        yield edge[starts], counts, forward
        start = stop


def sides_pair_up_exactly(source_blocks, doubtful: np.ndarray) -> bool:
    """Whether the sides whose keys are in ``doubtful`` (from ``doubtful_edges``) pair up when
    their end points are compared exactly (one use each way of every exact edge).

    Parameters
    ----------
    source_blocks : iterable of (k, 3, 3) arrays
        The triangles again, in blocks.
    doubtful : (d,) uint64, sorted
    """
    start, end = sides_of_edges(source_blocks, doubtful)
    if start.shape[0] == 0:
        return False
    # Undirected edge: its two end points in lexicographic order; direction: which came first.
    swap = _lex_less(end, start)
    lo = np.where(swap[:, None], end, start)
    hi = np.where(swap[:, None], start, end)
    _, inverse, counts = np.unique(np.concatenate([lo, hi], axis=1), axis=0,
                                   return_inverse=True, return_counts=True)
    forward = np.bincount(inverse.reshape(-1), weights=~swap, minlength=counts.size)
    return bool((counts == 2).all() and (forward == 1).all())


def sides_of_edges(source_blocks, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Start and end points ``(k, 3)`` of every side whose edge id (key without its direction
    bit) is in the sorted ``edges``; ``-0.0`` read as ``0.0``.

    Parameters
    ----------
    source_blocks : iterable of (k, 3, 3) arrays
        The triangles again, in blocks.
    edges : (d,) uint64, sorted
    """
    ends = []
    for block in source_blocks:
        cols = columns(block)
        if cols.shape[2] == 0:
            continue
        keys, keep = side_keys(cols)
        hit = np.isin(keys >> _ONE, edges)
        if not hit.any():
            continue
        # Corner coordinates in the keys' (slot, face) layout, +0.0 so -0.0 equals 0.0.
        corners = np.moveaxis(cols, 1, 2) + 0.0            # (slot, face, axis)
        start, end = corners, corners[[1, 2, 0]]
        if keep is not None:
            start, end = start[keep], end[keep]
        ends.append(np.concatenate([start.reshape(-1, 3)[hit], end.reshape(-1, 3)[hit]], axis=1))
    if not ends:
        return np.zeros((0, 3)), np.zeros((0, 3))
    sides = np.concatenate(ends)
    return sides[:, :3], sides[:, 3:]


def _lex_less(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise ``tuple(a) < tuple(b)`` for ``(k, 3)`` arrays."""
    less = a[:, 2] < b[:, 2]
    for axis in (1, 0):
        less = (a[:, axis] < b[:, axis]) | ((a[:, axis] == b[:, axis]) & less)
    return less


def vertex_ids(points: np.ndarray) -> np.ndarray:
    """Exact ids of points: equal coordinates get equal ids.

    Parameters
    ----------
    points : (m, 3) float

    Returns
    -------
    (m,) int64
    """
    coords = np.asarray(points, dtype=np.float64) + 0.0
    _, inverse = np.unique(coords, axis=0, return_inverse=True)
    return inverse.reshape(-1)


def closed_exact(triangles: np.ndarray) -> bool:
    """The closed test with exact vertex ids (slow path, no hashing)."""
    n = len(triangles)
    if n == 0:
        return False
    ids = vertex_ids(np.asarray(triangles).reshape(-1, 3)).reshape(n, 3)
    start = ids.reshape(-1)
    end = np.roll(ids, -1, axis=1).reshape(-1)
    keep = start != end
    start, end = start[keep], end[keep]
    if start.size == 0:
        return False  # faces that are single points bound nothing
    directed = np.stack([start, end], axis=1)
    uniq, counts = np.unique(directed, axis=0, return_counts=True)
    if (counts != 1).any():
        return False
    reverse = np.stack([end, start], axis=1)
    return bool(np.array_equal(np.unique(reverse, axis=0), uniq))
