"""Edges of a triangle soup: the face sides grouped by undirected edge, and edge samples.

The sides are read in the corners' vertex order (``vertices.group_corners``): each side is
taken at its end with the smaller vertex id, so the sequence comes out already sorted by that
end and only needs sorting by the other end within each vertex (a few sides). Python's (and
numpy's) stable sort, timsort, finds those runs, so sorting the ``3n`` sides costs a few linear
passes instead of an ``n log n`` sort. Each side's key packs the edge ``lo * m + hi`` (exact
vertex ids, so the key is exact), the side's index (``3 f + k``: from corner ``k`` of face
``f`` to corner ``k + 1``) and its direction (``lo`` first) into one int64 when it fits; the
groups of equal edges then list their sides in file order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.vertices import CHUNK, Corners


@dataclass
class Edges:
    """Sides sorted by undirected edge (then file order), and the groups they form.

    ``side`` and ``forward`` are per side; ``starts`` and ``counts`` delimit the groups (one
    per edge); ``boundary``, ``nonmanifold`` and ``misoriented`` hold group numbers.
    """

    side: np.ndarray
    forward: np.ndarray
    starts: np.ndarray
    counts: np.ndarray
    boundary: np.ndarray
    nonmanifold: np.ndarray
    misoriented: np.ndarray
    #: Free room of ``side.size`` int32 in the sides' buffer, for a per-side array (or None).
    spare: np.ndarray | None = None

    @property
    def count(self) -> int:
        return int(self.starts.size)

    @property
    def face(self) -> np.ndarray:
        return self.side // 3


def lone_sides(sides: np.ndarray) -> Edges:
    """The boundary sides ``sides`` (ascending side indices ``3 f + k``) as their own groups,
    one side each: the problem groups of a mesh whose every other edge is used once each way
    (as ``p3d_cli.mesh.paired``'s path finds it), which are all its readers look at. The edges
    used twice are not listed (``count`` is the boundary's), and ``forward`` is None."""
    b = int(sides.size)
    index = np.int32 if b < 2**31 else np.int64
    none = np.zeros(0, dtype=np.int64)
    return Edges(np.asarray(sides, dtype=np.int64), None, np.arange(b, dtype=index), np.ones(b, dtype=index),
                 boundary=np.arange(b, dtype=np.int64), nonmanifold=none, misoriented=none)


#: Offsets from corner ``3 f + k`` to the next and previous corner of face ``f``, by ``k``.
_NEXT = np.array([1, 1, -2], dtype=np.int64)
_PREVIOUS = np.array([2, -1, -1], dtype=np.int64)
#: ``c // 3 == (c * _THIRD) >> 33`` exactly for ``0 <= c < 2**32`` (the product fits in 64
#: bits): a multiply and a shift instead of numpy's much slower integer division.
_THIRD = np.uint64(0xAAAAAAAB)


def corner_slot(c: np.ndarray) -> np.ndarray:
    """``c % 3`` of non-negative int64 corner indices (``k`` of corner ``3 f + k``)."""
    if c.size and int(c.max()) >= 2**32:
        return c % 3
    third = (c.view(np.uint64) * _THIRD) >> np.uint64(33)
    return c - 3 * third.view(np.int64)


def next_corner(c: np.ndarray) -> np.ndarray:
    """The next corner of the same face (``3 f + (k + 1) % 3``), as int64."""
    c = np.asarray(c, dtype=np.int64)
    if c.ndim == 0:
        return c + (1 if c % 3 < 2 else -2)
    return c + _NEXT[corner_slot(c)]


def group_edges(corners: Corners, packed: bool | None = None) -> Edges:
    """The edges of the grouped corners; frees ``corners.keys`` once read.

    Parameters
    ----------
    corners : Corners
    packed : bool, optional
        Force (True) or forbid (False) the one-int64 key; default: packed when it fits.
    """
    m, sides = corners.count, corners.ids.size
    side_bits = max(int(sides - 1).bit_length(), 1)
    fits = (max(m * m - 1, 1)).bit_length() + side_bits + 1 <= 63
    if fits and packed is not False:
        keys = _emit_packed(corners, side_bits)
        corners.keys = None
        keys.sort(kind="stable")                        # timsort: runs per vertex
        side, forward, starts = _unpack(keys, side_bits)
        spare = None
        if keys.size == sides and side.dtype == np.int32:
            # Every side kept: the int32 sides fill the first half of the keys' buffer, so
            # the second half is free for one more per-side array (the fans' twins).
            spare = keys.view(np.int32)[sides:]
    else:
        edge, extra = _emit_unpacked(corners)
        corners.keys = None
        order = np.lexsort((extra, edge))
        edge, extra = edge[order], extra[order]
        side, forward = (extra >> 1).astype(corners.ids.dtype), (extra & 1).astype(bool)
        starts = _group_starts(lambda a, b: edge[a:b], edge.size)
        spare = None
    index = np.int32 if side.size < 2**31 else np.int64
    starts = starts.astype(index)
    counts = np.diff(np.append(starts, index(side.size)))
    return Edges(side, forward, starts, counts, boundary=np.flatnonzero(counts == 1),
                 nonmanifold=np.flatnonzero(counts > 2),
                 misoriented=_misoriented(forward, starts, counts), spare=spare)


def _misoriented(forward: np.ndarray, starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Groups of two sides that run the same way, found in slices (small temporaries)."""
    found = []
    for lo in range(0, starts.size, CHUNK):
        pairs = np.flatnonzero(counts[lo:lo + CHUNK] == 2) + lo
        first = starts[pairs]
        found.append(pairs[forward[first] == forward[first + 1]])
    return np.concatenate(found) if found else np.zeros(0, dtype=np.int64)


def _chunk_sides(corners: Corners, lo: int, hi: int):
    """For sorted positions ``lo:hi``: vertex ``v``, corner ``c``, and the sides at ``c``.

    Side ``c`` runs ``v -> w`` (to the next corner); side ``before`` runs ``u -> v``.
    """
    first = corners.first
    c = corners.corner(lo, hi)
    # Vertex of each sorted position, from the group boundaries (no gather).
    va = int(np.searchsorted(first, lo, side="right")) - 1
    vb = int(np.searchsorted(first, hi, side="left"))
    counts = np.minimum(first[va + 1:vb + 1], hi) - np.maximum(first[va:vb], lo)
    v = np.repeat(np.arange(va, vb, dtype=np.int64), counts)
    slot = corner_slot(c)
    after = c + _NEXT[slot]
    before = c + _PREVIOUS[slot]
    return v, c, corners.ids[after], before, corners.ids[before]


def _emit_packed(corners: Corners, side_bits: int) -> np.ndarray:
    """Every non-degenerate side once, at its smaller-id end, in the corners' sorted order:
    ``(lo * m + hi) << (side_bits + 1) | side << 1 | (lo first)``.

    Written into the sorted corner keys' own buffer, from the end: the sides taken at the
    last ``r`` sorted corners have both ends among those corners' vertices, so there are at
    most ``r`` of them (each corner starts one side), and they only ever overwrite keys
    already read. No second ``3n`` array.
    """
    ids, m, shift = corners.ids, np.int64(corners.count), np.int64(side_bits + 1)
    out = corners.keys.view(np.int64)
    top = ids.size
    for lo in reversed(range(0, ids.size, CHUNK)):
        v, c, w, before, u = _chunk_sides(corners, lo, min(lo + CHUNK, ids.size))
        key_out = v * m
        key_out += w
        key_out <<= shift
        key_out |= (c << 1) | 1
        key_in = v * m
        key_in += u
        key_in <<= shift
        key_in |= before << 1
        parts = key_out[v < w], key_in[u > v]
        top -= parts[0].size + parts[1].size
        out[top:top + parts[0].size] = parts[0]
        out[top + parts[0].size:top + parts[0].size + parts[1].size] = parts[1]
    return out[top:]


def _emit_unpacked(corners: Corners):
    """As ``_emit_packed``, for meshes too large to pack: edge keys and ``side << 1 | fwd``."""
    ids, m = corners.ids, np.int64(corners.count)
    edges, extras = [], []
    for lo in range(0, ids.size, CHUNK):
        v, c, w, before, u = _chunk_sides(corners, lo, min(lo + CHUNK, ids.size))
        take_out, take_in = v < w, u > v
        edges += [v[take_out] * m + w[take_out], v[take_in] * m + u[take_in]]
        extras += [(c[take_out] << 1) | 1, before[take_in] << 1]
    return np.concatenate(edges), np.concatenate(extras)


def _unpack(keys: np.ndarray, side_bits: int):
    """Sides, directions and edge group starts of the sorted packed keys, in slices."""
    # The sides go into the keys' own buffer, viewed as int32 when they fit: side[i] takes
    # bytes 4i..4i+4, which belong to keys already read, so no second 3n-array is needed.
    side = keys.view(np.int32)[:keys.size] if keys.size < 2**31 else keys
    forward = np.empty(keys.size, dtype=bool)
    mask, shift = np.int64((1 << side_bits) - 1), np.int64(side_bits + 1)
    starts, previous = [], None
    for lo in range(0, keys.size, CHUNK):
        part = keys[lo:lo + CHUNK]
        edge = part >> shift
        forward[lo:lo + part.size] = part & 1
        side[lo:lo + part.size] = (part >> 1) & mask        # last: overwrites keys read
        new = np.empty(edge.size, dtype=bool)
        new[0] = previous is None or edge[0] != previous
        np.not_equal(edge[1:], edge[:-1], out=new[1:])
        starts.append((np.flatnonzero(new) + lo).astype(side.dtype))
        previous = edge[-1]
    starts = np.concatenate(starts) if starts else np.zeros(0, dtype=side.dtype)  # type: ignore[assignment]  # the list becomes its array
    return side, forward, starts


def _group_starts(edge_of, size: int) -> np.ndarray:
    """Positions where the sorted edge value changes, computed in slices (small temporaries)."""
    starts, previous = [], None
    for lo in range(0, size, CHUNK):
        edge = edge_of(lo, min(lo + CHUNK, size))
        new = np.empty(edge.size, dtype=bool)
        new[0] = previous is None or edge[0] != previous
        np.not_equal(edge[1:], edge[:-1], out=new[1:])
        starts.append(np.flatnonzero(new) + lo)
        previous = edge[-1]
    return np.concatenate(starts) if starts else np.zeros(0, dtype=np.int64)
