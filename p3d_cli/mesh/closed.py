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


def _mix(z: np.ndarray) -> np.ndarray:
    """The splitmix64 finalizer, in place on a uint64 array (wrapping arithmetic)."""
    z ^= z >> np.uint64(30)
    z *= _M1
    z ^= z >> np.uint64(27)
    z *= _M2
    z ^= z >> np.uint64(31)
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
    first, second = keys[0::2], keys[1::2]
    if not np.array_equal(first >> np.uint64(1), second >> np.uint64(1)):
        return False
    if (first & np.uint64(1)).any() or not (second & np.uint64(1)).all():
        return False
    # No edge used by a third face: the next pair must be a different edge.
    return not bool(((first[1:] >> np.uint64(1)) == (second[:-1] >> np.uint64(1))).any())


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
    directed = np.stack([start, end], axis=1)
    uniq, counts = np.unique(directed, axis=0, return_counts=True)
    if (counts != 1).any():
        return False
    reverse = np.stack([end, start], axis=1)
    return bool(np.array_equal(np.unique(reverse, axis=0), uniq))
