"""Pairs of faces whose bounding boxes overlap: a hierarchical grid, never all pairs.

Each face's axis-aligned box (closed, rounded outwards to float32: never smaller than the
face's exact box) is assigned a *level*: the smallest ``L`` whose cell size ``c · 2**L`` is at
least the box's largest extent, ``c`` being the typical extent of the mesh's faces. At its own
level a box spans at most two cells along each axis, so a face is entered in at most eight
cells. Two boxes that overlap then share a cell at the coarser level of the two:

- faces of the same level are paired within each cell (their entries sorted by cell: one
  ``numpy.sort`` of packed 64-bit keys ``cell | face``);
- a face of a finer level is looked up in the cells of each coarser level that holds faces
  (at most eight cells per level, usually one or two), and paired with the faces there.

A pair that shares several cells is kept in one only: the cell whose coordinates are, along
each axis, the larger of the two boxes' first cells (the cell holding the lower corner of the
boxes' intersection). Each entry carries three bits saying along which axes its face starts in
the entry's cell; a pair is kept where, along every axis, one of the two starts. Kept pairs
are then filtered by the exact box overlap test.

The work is linear in the number of faces for meshes whose faces are of a few sizes (a scan,
a tessellated CAD part), plus the number of overlapping pairs; pairs come out in chunks so that
memory stays bounded. References: the uniform grid and its hierarchical form for collision
detection (C. Ericson, *Real-Time Collision Detection*, Morgan Kaufmann 2005, ch. 7).
"""

from __future__ import annotations

from typing import Iterator

import numpy as np

#: Candidate pairs handled per vectorised step (the temporaries stay in cache).
PAIR_CHUNK = 1 << 16
#: The typical extent: this quantile of the faces' largest box extents (faces above it go to
#: coarser levels, whose cells are twice as large per level).
TYPICAL = 0.75


def outward_boxes(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float64 boxes as float32 boxes that contain them (rounded down and up)."""
    lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)
    low = lo32.astype(np.float64) > lo
    lo32[low] = np.nextafter(lo32[low], np.float32(-np.inf))
    high = hi32.astype(np.float64) < hi
    hi32[high] = np.nextafter(hi32[high], np.float32(np.inf))
    return lo32, hi32


Pairs = Iterator[tuple[np.ndarray, np.ndarray]]


def box_pairs(lo: np.ndarray, hi: np.ndarray, faces: np.ndarray | None = None) -> Pairs:
    """Chunks ``(i, j)`` of face pairs whose closed boxes overlap, each pair once, ``i != j``.

    Parameters
    ----------
    lo, hi : (n, 3) float32
        Box corners (finite), from ``outward_boxes``.
    faces : (n,) int, optional
        The face number of each box (default ``0..n-1``): boxes of faces left out of the test
        (degenerate ones) are simply not passed.

    Yields
    ------
    (k,) int64, (k,) int64
        Face numbers, in no particular order within a pair.
    """
    n = len(lo)
    if faces is None:
        faces = np.arange(n, dtype=np.int64)
    if n < 2:
        return
    extent = (hi - lo).max(axis=1).astype(np.float64)
    cell = float(np.quantile(extent, TYPICAL)) if n > 1 else 0.0
    if not cell > 0:
        positive = extent[extent > 0]
        cell = float(positive.min()) if positive.size else 1.0
    # The grid's origin and the cell size: floor((x - origin) / size) for every coordinate.
    origin = lo.min(axis=0).astype(np.float64)
    level = np.zeros(n, dtype=np.int64)
    big = extent > cell
    level[big] = np.ceil(np.log2(extent[big] / cell)).astype(np.int64)
    # log2 rounds: make sure every box fits its level's cells (at most two per axis).
    while True:
        short = extent > cell * np.exp2(level)
        if not short.any():
            break
        level[short] += 1
    levels = np.unique(level)
    grids = {int(L): _Grid(lo, hi, np.flatnonzero(level == L), origin, cell * 2.0 ** int(L)) for L in levels}
    for L, grid in grids.items():
        for i, j in grid.own_pairs():
            yield faces[i], faces[j]
        # Finer faces whose boxes meet the box of this level's faces.
        finer = np.flatnonzero((level < L) & (lo <= grid.box_hi).all(axis=1) & (hi >= grid.box_lo).all(axis=1))
        for start in range(0, finer.size, PAIR_CHUNK):
            for i, j in grid.probe(finer[start:start + PAIR_CHUNK]):
                yield faces[i], faces[j]


class _Grid:
    """The faces of one level, entered in every cell their boxes overlap, sorted by cell."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, members: np.ndarray, origin: np.ndarray, size: float):
        self.lo, self.hi, self.origin, self.size = lo, hi, origin, size
        top = np.zeros(3, dtype=np.int64)
        total = 0
        for part in _slices(members):
            last = self.cells(hi[part])
            top = np.maximum(top, last.max(axis=0))
            total += int((last - self.cells(lo[part]) + 1).prod(axis=1).sum())
        self.bits = [max(int(t + 2).bit_length(), 1) for t in top]  # room for probes beyond
        self.face_bits = max(int(len(lo) - 1).bit_length(), 1)
        packed = sum(self.bits) + self.face_bits + 3 <= 63
        # One 64-bit key per entry, ``cell | face | start bits``, sorted in place: no argsort.
        keys = np.empty(total, dtype=np.int64)
        faces = None if packed else np.empty(total, dtype=np.int64)
        done = 0
        for part in _slices(members):
            face, coords, starts = self._entries(part)
            key = self.pack(coords)
            if packed:
                keys[done:done + key.size] = (key << (self.face_bits + 3)) | (face << 3) | starts
            else:
                keys[done:done + key.size] = (key << 3) | starts
                faces[done:done + key.size] = face
            done += key.size
        index = np.int32 if len(lo) < 2**31 else np.int64
        if packed:
            keys.sort()
            self.face = ((keys >> 3) & ((1 << self.face_bits) - 1)).astype(index)
            self.start = (keys & 7).astype(np.int8)
            keys >>= self.face_bits + 3
        else:
            order = np.lexsort((faces, keys))
            keys, self.face = keys[order], faces[order].astype(index)
            del faces, order
            self.start = (keys & 7).astype(np.int8)
            keys >>= 3
        self.size_entries = keys.size
        new = np.ones(keys.size, dtype=bool)
        np.not_equal(keys[1:], keys[:-1], out=new[1:])
        self.cell_start = np.flatnonzero(new)
        self.cell_key = keys[self.cell_start]
        self.cell_end = np.append(self.cell_start[1:], keys.size)
        self.box_lo, self.box_hi = lo[members].min(axis=0), hi[members].max(axis=0)

    def _entries(self, part: np.ndarray):
        """``(face, cell coordinates, start bits)`` of every cell the boxes of ``part`` overlap."""
        first, last = self.cells(self.lo[part]), self.cells(self.hi[part])
        span = last - first + 1                             # 1 or 2 per axis at a face's level
        count = span.prod(axis=1)
        face = np.repeat(part, count)
        step = np.arange(face.size) - np.repeat(np.cumsum(count) - count, count)
        sx, sy = np.repeat(span[:, 0], count), np.repeat(span[:, 1], count)
        offset = np.stack([step % sx, (step // sx) % sy, step // (sx * sy)], axis=1)
        # Bit k: the face's box starts in this cell along axis k (see the module docstring).
        starts = (offset == 0) @ np.array([1, 2, 4])
        return face, np.repeat(first, count, axis=0) + offset, starts

    def cells(self, x: np.ndarray) -> np.ndarray:
        """Integer cell coordinates ``(k, 3)`` of points (monotone in each coordinate)."""
        return np.floor((x.astype(np.float64) - self.origin) / self.size).astype(np.int64)

    def pack(self, coords: np.ndarray) -> np.ndarray:
        by, bz = self.bits[1], self.bits[2]
        return (coords[:, 0] << (by + bz)) | (coords[:, 1] << bz) | coords[:, 2]

    def own_pairs(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Pairs of this level's faces that share a cell (kept in their owner cell)."""
        end = np.repeat(self.cell_end, self.cell_end - self.cell_start)
        after = end - np.arange(self.size_entries) - 1          # partners later in the same cell
        yield from self._pairs_after(after)

    def probe(self, queries: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """Pairs of finer faces ``queries`` with this level's faces in the cells they overlap."""
        who, coords, starts = self._entries(queries)
        inside = ((coords >= 0) & (coords < (1 << np.array(self.bits)))).all(axis=1)
        who, key, starts = who[inside], self.pack(coords[inside]), starts[inside]
        at = np.minimum(np.searchsorted(self.cell_key, key), self.cell_key.size - 1)
        hit = self.cell_key[at] == key
        who, at, starts = who[hit], at[hit], starts[hit]
        begin, size = self.cell_start[at], self.cell_end[at] - self.cell_start[at]
        for index, step in _items(size):        # (probe, every entry of its cell)
            entry = begin[index] + step
            keep = (starts[index] | self.start[entry]) == 7
            yield from _overlapping(self.lo, self.hi, who[index][keep], self.face[entry][keep])

    def _pairs_after(self, after: np.ndarray):
        for index, step in _items(after):       # (entry p, entry p + 1 + step)
            q = index + 1 + step
            keep = (self.start[index] | self.start[q]) == 7
            yield from _overlapping(self.lo, self.hi, self.face[index][keep], self.face[q][keep])


def _slices(members: np.ndarray, step: int = PAIR_CHUNK) -> Iterator[np.ndarray]:
    for lo in range(0, members.size, step):
        yield members[lo:lo + step]


def _items(counts: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Chunks of the items ``(t, s)``, ``0 <= s < counts[t]``, in order, as two arrays."""
    ends = np.cumsum(counts)
    total = int(ends[-1]) if ends.size else 0
    for lo in range(0, total, PAIR_CHUNK):
        hi = min(lo + PAIR_CHUNK, total)
        a = int(np.searchsorted(ends, lo, side="right"))
        b = int(np.searchsorted(ends, hi, side="left")) + 1
        part = counts[a:b].astype(np.int64)
        skip = lo - (int(ends[a]) - int(counts[a]))
        part[0] -= skip
        part[-1] -= int(ends[b - 1]) - hi
        index = np.repeat(np.arange(a, b), part)
        step = np.arange(index.size) - np.repeat(np.cumsum(part) - part, part)
        step[:part[0]] += skip
        yield index, step


def _overlapping(lo: np.ndarray, hi: np.ndarray, i: np.ndarray, j: np.ndarray):
    """The pairs of ``(i, j)`` whose closed boxes overlap (one chunk, or nothing)."""
    if i.size == 0:
        return
    keep = (lo[i, 0] <= hi[j, 0]) & (lo[j, 0] <= hi[i, 0])
    keep &= (lo[i, 1] <= hi[j, 1]) & (lo[j, 1] <= hi[i, 1])
    keep &= (lo[i, 2] <= hi[j, 2]) & (lo[j, 2] <= hi[i, 2])
    keep &= i != j
    if keep.any():
        yield i[keep], j[keep]
