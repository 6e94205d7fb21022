"""Is a triangle soup closed? Edge matching by exact vertex coordinates, in one sort.

"Closed" means every edge is shared by exactly two faces that traverse it in opposite
directions, vertices being matched by their exact coordinates (no tolerance, no welding;
``-0.0`` equals ``0.0``). This needs no vertex merging: each corner's coordinates are hashed
to 64 bits, each directed edge to a key whose high 63 bits identify the undirected edge and
whose low bit gives its direction; the mesh is closed when, after one sort, the keys pair up as
(direction 0, direction 1) with no third use. A hash collision could only make a closed mesh
look open (never the reverse, barring a second, matching collision), so a "not closed" verdict
is confirmed with exact vertex ids before it is reported.
"""

from __future__ import annotations

import numpy as np

_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)


_S30, _S27, _S31 = np.uint64(30), np.uint64(27), np.uint64(31)
_ONE = np.uint64(1)


def _mix(z: np.ndarray, scratch: np.ndarray | None = None) -> np.ndarray:
    """The splitmix64 finalizer, in place on a uint64 array (wrapping arithmetic).

    ``scratch``, an array like ``z``, saves the three temporaries of the shifts.
    """
    if scratch is None:
        scratch = np.empty_like(z)
    z ^= np.right_shift(z, _S30, out=scratch)
    z *= _M1
    z ^= np.right_shift(z, _S27, out=scratch)
    z *= _M2
    z ^= np.right_shift(z, _S31, out=scratch)
    return z


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
    h = _mix(bits[..., 0] ^ _GOLDEN)
    h ^= bits[..., 1]
    h = _mix(h)
    h ^= bits[..., 2]
    return _mix(h)


def column_edge_keys(columns: np.ndarray) -> np.ndarray:
    """``directed_edge_keys(corner_hashes(triangles))`` for triangles given as columns.

    The same keys (in another order, which the sort makes irrelevant), computed with reused
    buffers from the layout the one-pass analysis already holds.

    Parameters
    ----------
    columns : (3, 3, n) float64
        Vertex slot, axis, triangle; exact world coordinates (not shifted).

    Returns
    -------
    (m,) uint64
    """
    n = columns.shape[2]
    scratch = np.empty((3, n), dtype=np.uint64)
    # Same hash as corner_hashes: mix(mix(mix(x ^ G) ^ y) ^ z) of the float64 bits, after
    # adding 0.0 so that -0.0 and 0.0 hash alike.
    coord = np.empty((3, n))
    h = np.add(columns[:, 0], 0.0, out=coord).view(np.uint64).copy()
    h ^= _GOLDEN
    _mix(h, scratch)
    h ^= np.add(columns[:, 1], 0.0, out=coord).view(np.uint64)
    _mix(h, scratch)
    h ^= np.add(columns[:, 2], 0.0, out=coord).view(np.uint64)
    _mix(h, scratch)
    start, end = h, h[[1, 2, 0]]            # edges 0→1, 1→2, 2→0 of every triangle
    if (start == end).any():                # rare: a degenerate edge bounds nothing
        keep = start != end
        start, end = start[keep], end[keep]
        scratch = np.empty_like(start)
    forward = start < end
    key = np.minimum(start, end)
    high = np.maximum(start, end, out=end)
    key *= _GOLDEN
    key += high
    _mix(key, scratch)
    key &= ~_ONE
    key |= forward
    return key.reshape(-1)


def directed_edge_keys(hashes: np.ndarray) -> np.ndarray:
    """Keys of the directed edges (0→1, 1→2, 2→0) of each triangle.

    Parameters
    ----------
    hashes : (n, 3) uint64
        Corner hashes from ``corner_hashes``.

    Returns
    -------
    (m,) uint64
        Bit 0 is the direction (1 when the edge runs from the smaller hash to the larger), the
        other bits identify the undirected edge. Edges whose two ends are the same point are
        left out: they bound nothing.
    """
    start = hashes.reshape(-1)
    end = np.roll(hashes, -1, axis=1).reshape(-1)
    keep = start != end
    start, end = start[keep], end[keep]
    low = np.minimum(start, end)
    high = np.maximum(start, end)
    key = _mix(low * _GOLDEN + high)
    key &= ~np.uint64(1)
    key |= (start < end).astype(np.uint64)
    return key


def keys_pair_up(keys: np.ndarray) -> bool:
    """True when the sorted keys come in (direction 0, direction 1) pairs of one edge each.

    Sorts ``keys`` in place.
    """
    if keys.size == 0 or keys.size % 2:
        return False
    keys.sort()
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
