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

    @property
    def count(self) -> int:
        return int(self.starts.size)

    @property
    def face(self) -> np.ndarray:
        return self.side // 3


def next_corner(c: np.ndarray) -> np.ndarray:
    """The next corner of the same face (``3 f + (k + 1) % 3``)."""
    return c + np.where(c % 3 == 2, -2, 1)


def group_edges(corners: Corners, packed: bool | None = None) -> Edges:
    """The edges of the grouped corners.

    Parameters
    ----------
    corners : Corners
    packed : bool, optional
        Force (True) or forbid (False) the one-int64 key; default: packed when it fits.
    """
    m, sides = corners.count, corners.ids.size
    side_bits = max(int(sides - 1).bit_length(), 1)
    fits = (max(m * m - 1, 1)).bit_length() + side_bits + 1 <= 63
    packed = fits if packed is None else packed and fits
    keys, extra = _emit_sides(corners, side_bits, packed)
    if packed:
        keys.sort(kind="stable")                        # timsort: runs per vertex
        side = ((keys >> 1) & ((1 << side_bits) - 1)).astype(corners.ids.dtype)
        forward = (keys & 1).astype(bool)
        edge_of = lambda a, b: keys[a:b] >> (side_bits + 1)  # noqa: E731
    else:
        order = np.lexsort((extra, keys))
        keys, extra = keys[order], extra[order]
        side, forward = (extra >> 1).astype(corners.ids.dtype), (extra & 1).astype(bool)
        edge_of = lambda a, b: keys[a:b]                # noqa: E731
    starts = _group_starts(edge_of, keys.size)
    del keys, extra
    counts = np.diff(np.append(starts, side.size))
    pairs = np.flatnonzero(counts == 2)
    same_way = forward[starts[pairs]] == forward[starts[pairs] + 1]
    return Edges(side, forward, starts, counts, boundary=np.flatnonzero(counts == 1),
                 nonmanifold=np.flatnonzero(counts > 2), misoriented=pairs[same_way])


def _emit_sides(corners: Corners, side_bits: int, packed: bool):
    """Every non-degenerate side once, at its smaller-id end, in the corners' sorted order."""
    ids, first, m = corners.ids, corners.first, np.int64(corners.count)
    out_keys, out_extra = [], []
    for lo in range(0, ids.size, CHUNK):
        hi = min(lo + CHUNK, ids.size)
        c = corners.corner(lo, hi)
        # Vertex of each sorted position, from the group boundaries (no gather).
        va = int(np.searchsorted(first, lo, side="right")) - 1
        vb = int(np.searchsorted(first, hi, side="left"))
        counts = (np.minimum(first[va + 1:vb + 1], hi) - np.maximum(first[va:vb], lo))
        v = np.repeat(np.arange(va, vb, dtype=np.int64), counts)
        slot = c % 3
        after = c + np.where(slot == 2, -2, 1)
        before = c + np.where(slot == 0, 2, -1)
        w = ids[after].astype(np.int64)                 # side c runs v -> w
        u = ids[before].astype(np.int64)                # side `before` runs u -> v
        take_out, take_in = v < w, u > v
        edge = np.concatenate([v[take_out] * m + w[take_out], v[take_in] * m + u[take_in]])
        extra = np.concatenate([(c[take_out] << 1) | 1, before[take_in] << 1])
        if packed:
            out_keys.append((edge << (side_bits + 1)) | extra)
        else:
            out_keys.append(edge)
            out_extra.append(extra)
    empty = np.zeros(0, dtype=np.int64)
    keys = np.concatenate(out_keys) if out_keys else empty
    extra = np.concatenate(out_extra) if out_extra else None
    return keys, extra


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
