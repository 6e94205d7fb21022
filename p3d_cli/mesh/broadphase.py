"""Pairs of faces whose bounding boxes overlap: a hierarchical grid, never all pairs.

Each face's axis-aligned box (closed, rounded outwards to float32: never smaller than the
face's exact box) is assigned a *level*: the smallest ``L`` whose cell size ``c · 2**L`` is at
least the box's largest extent, ``c`` being the typical extent of the mesh's faces. At its own
level a box spans at most two cells along each axis, so a face is entered in at most eight
cells. Two boxes that overlap then share a cell at the coarser level of the two:

- faces of the same level are paired within each cell (their entries sorted by cell: one
  ``numpy.sort`` of packed 64-bit keys ``cell | face | bits``), the cells of each size at
  once, from the upper triangle of a table of that size (no per-pair index arithmetic);
- a face of a finer level is looked up in the cells of each coarser level that holds faces
  (at most eight cells per level, usually one or two), and paired with the faces there.

A pair that shares several cells is kept in one only: the cell whose coordinates are, along
each axis, the larger of the two boxes' first cells (the cell holding the lower corner of the
boxes' intersection). Each entry carries three bits saying along which axes its face starts in
the entry's cell; a pair is kept where, along every axis, one of the two starts.

Pairs are tested within their cell on boxes quantised to 1/256 of the cell, rounded outwards
by a step (so never smaller), packed six 9-bit fields to a 64-bit word: the upper corner and
the complement of the lower corner, ``[hx, hy, hz, 255-lx, 255-ly, 255-lz]``, and the lower
word ``[lx, ly, lz, 255-hx, 255-hy, 255-hz]``. Boxes i and j overlap along every axis exactly
when every field of ``H_j`` is at least the one of ``L_i``, which one subtraction decides for
all six (a guard bit per field stays set where the field did not borrow; a SIMD-within-a-
register compare). The start bits ride in the same words. So a candidate pair costs two
loads and a few integer operations. A pair whose quantised boxes meet may still have boxes
that do not (within a step of each other): the callers test faces exactly anyway, and
``box_pairs`` filters them when exact box pairs are wanted.

Levels are cut into slabs along x of at most ``SLAB`` entries, each sorted and paired on its
own (a cell belongs to one slab, so a pair is still kept once), which bounds the memory.
The work is linear in the number of faces for meshes whose faces are of a few sizes (a scan,
a tessellated CAD part), plus the number of overlapping pairs. References: the uniform grid
and its hierarchical form (C. Ericson, *Real-Time Collision Detection*, Morgan Kaufmann 2005,
ch. 7); SIMD within a register (H. S. Warren, *Hacker's Delight*, 2nd ed., 2012, ch. 2).
"""

from __future__ import annotations

from typing import Iterator

import numpy as np

from p3d_cli.mesh.cell_pairs import BYTE, FIELD, PAIR_CHUNK, START_SHIFT, cell_pairs, items, kept, meet

#: The typical extent: this quantile of the faces' largest box extents (faces above it go to
#: coarser levels, whose cells are twice as large per level).
TYPICAL = 0.9
#: Cell size as a multiple of the typical extent: larger cells hold more faces (more pairs
#: to test, which is cheap) but enter each face in fewer cells (fewer entries to sort).
SCALE = 2.0
#: Above this many bits in a cell key, a slab ranks its cells' coordinates (``_Grid``).
SPARSE_BITS = 60
#: Entries per slab of a level's grid (bounds the memory of the sort).
SLAB = 1 << 18

Pairs = Iterator[tuple[np.ndarray, np.ndarray]]
Blocks = Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]


def outward_boxes(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """float64 boxes as float32 boxes that contain them (rounded down and up)."""
    lo32, hi32 = lo.astype(np.float32), hi.astype(np.float32)
    low = lo32.astype(np.float64) > lo
    lo32[low] = np.nextafter(lo32[low], np.float32(-np.inf))
    high = hi32.astype(np.float64) < hi
    hi32[high] = np.nextafter(hi32[high], np.float32(np.inf))
    return lo32, hi32


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
    index = np.arange(len(lo)) if faces is None else np.asarray(faces)
    for members, p, q in pair_blocks(lo, hi):
        i, j = members[p], members[q]
        keep = _overlap(lo, hi, i, j)
        if keep.any():
            yield index[i[keep]], index[j[keep]]


def pair_blocks(lo: np.ndarray, hi: np.ndarray) -> Blocks:
    """``(members, p, q)``: the box numbers ``members`` of a block of grid cells and the pairs
    ``(members[p], members[q])`` among them whose quantised boxes overlap (every overlapping
    pair of boxes once, and a few within a quantisation step). A block holds a run of cells,
    so the callers gather each face's data once per block, then index it locally per pair."""
    n = len(lo)
    if n < 2:
        return
    cell, origin, level, top = _levels(lo, hi)
    levels = np.unique(level).tolist()
    for L in levels:
        members = np.flatnonzero(level == L).astype(np.int32 if n < 2**31 else np.int64)
        size = cell * 2.0 ** L
        for x0, x1 in _slabs(lo, hi, members, origin, size):
            grid = _Grid(lo, hi, members, origin, size, x0, x1, top)
            yield from grid.own_blocks()
            if L == levels[0]:
                continue                         # no finer faces to look up
            # Finer faces whose boxes meet the box of this slab's faces.
            box_lo, box_hi = grid.box()
            near = level < L
            for k in range(3):
                near &= (lo[:, k] <= box_hi[k]) & (hi[:, k] >= box_lo[k])
            finer = np.flatnonzero(near)
            for start in range(0, finer.size, PAIR_CHUNK):
                yield from grid.probe(finer[start:start + PAIR_CHUNK])
            del grid


def _levels(lo: np.ndarray, hi: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """``(cell, origin, level, top)``: the finest cell size, the grid's origin (cells are
    ``floor((x - origin) / size)`` per coordinate), each box's level (its cell size
    ``cell * 2**level`` at least its largest extent), and the boxes' upper corner."""
    extent = np.maximum(np.maximum(hi[:, 0] - lo[:, 0], hi[:, 1] - lo[:, 1]), hi[:, 2] - lo[:, 2])
    cell, level = _levels_of(extent)
    return cell, lo.min(axis=0).astype(np.float64), level, hi.max(axis=0).astype(np.float64)


def _levels_of(extent: np.ndarray) -> tuple[float, np.ndarray]:
    """The finest cell size and each box's level, from the boxes' largest extents."""
    cell = float(np.quantile(extent, TYPICAL)) * SCALE
    if not cell > 0:
        positive = extent[extent > 0]
        cell = float(positive.min()) if positive.size else 1.0
    level = np.zeros(len(extent), dtype=np.int16)
    big = extent > cell
    level[big] = np.ceil(np.log2(extent[big].astype(np.float64) / cell)).astype(np.int16)
    # log2 rounds: make sure every box fits its level's cells (at most two per axis).
    while True:
        short = np.flatnonzero(big)[extent[big] > cell * np.exp2(level[big])]
        if not short.size:
            break
        level[short] += 1
    return cell, level


def box_frame(points: np.ndarray) -> tuple[np.ndarray, int]:
    """``(centre, shift)``: the faces' boxes are taken about the points' centre and scaled by
    ``2**shift`` to a span near 1 (far from the world origin float32 coordinates would be too
    coarse, every box 8 wide at 1e8; huge or tiny parts would over- or underflow)."""
    centre = (points.min(axis=0) + points.max(axis=0)) / 2 if len(points) else np.zeros(3)
    span = float(np.abs(points - centre).max()) if len(points) else 0.0
    return centre, (-int(np.frexp(span)[1]) if 0 < span < np.inf else 0)


#: Cells per axis at most: faces beyond are in the last cell (clamping keeps the cells monotone,
#: so every pair is still found, once; only parts 2**40 face sizes apart share such a cell).
_MAX_CELL = float(2 ** 40)


def _cells(x: np.ndarray, origin: np.ndarray, size: float) -> np.ndarray:
    """Integer cell coordinates ``(k, 3)`` of points (monotone in each coordinate)."""
    return np.clip(np.floor((x.astype(np.float64) - origin) / size), 0, _MAX_CELL).astype(np.int64)


def _slabs(lo, hi, members, origin, size) -> list[tuple[int, int]]:
    """Ranges of x cells ``[x0, x1)`` holding at most about ``SLAB`` entries each."""
    first = np.clip(np.floor((lo[members, 0].astype(np.float64) - origin[0]) / size), 0, _MAX_CELL).astype(np.int64)
    top = int(first.max()) + 3
    # Entries per x column (about: a face's entries all counted in its first column, at 4);
    # only the occupied columns when there are far more columns than faces.
    if top <= 4 * first.size + 1024:
        column = np.bincount(first, minlength=top) * 4.0
        where = np.arange(top)
    else:
        where, count = np.unique(first, return_counts=True)
        column = count * 4.0
    del first
    cuts, running, start = [], 0.0, 0
    for x, count in zip(where.tolist(), column.tolist()):
        if running and running + count > SLAB:
            cuts.append((start, x))
            start, running = x, 0.0
        running += count
    cuts.append((start, top))
    return cuts


class _Grid:
    """The faces of one level, entered in every cell of x range ``[x0, x1)`` their boxes
    overlap, sorted by cell; each entry with its packed words (module docstring)."""

    def __init__(self, lo, hi, members, origin, size: float, x0: int, x1: int, top: np.ndarray):
        self.lo, self.hi, self.origin, self.size = lo, hi, origin, size
        inside = np.empty(members.size, dtype=bool)
        for at in range(0, members.size, 1 << 18):
            part = members[at:at + (1 << 18)]
            first_x = np.clip(np.floor((lo[part, 0].astype(np.float64) - origin[0]) / size), 0, _MAX_CELL)
            last_x = np.clip(np.floor((hi[part, 0].astype(np.float64) - origin[0]) / size), 0, _MAX_CELL)
            inside[at:at + part.size] = (first_x < x1) & (last_x >= x0)
        members = members[inside]
        del inside
        self.x0, self.x1 = x0, x1
        # Room for every cell of the level (and a probe one beyond): the bits of a cell key.
        top = np.clip(np.floor((top - origin) / size), 0, _MAX_CELL).astype(np.int64) + 2
        self.bits = [max(int(t).bit_length(), 1) for t in top]
        self.axes: list[np.ndarray] | None = None
        entries = [self._entries(part) for part in _slices(members)]
        if sum(self.bits) > SPARSE_BITS:
            # A grid too wide for one 64-bit key (parts very far apart for their faces' size):
            # each axis's occupied coordinates are ranked (monotone, so the cells' order and
            # their neighbours' order are kept), and the keys pack the ranks.
            coords = np.concatenate([c for _, c, _ in entries]) if entries else np.zeros((0, 3), np.int64)
            self.axes = [np.unique(coords[:, a]) for a in range(3)]
            self.bits = [max(int(len(axis)).bit_length(), 1) for axis in self.axes]
            del coords
        self.face_bits = max(int(len(lo) - 1).bit_length(), 1)
        packed = sum(self.bits) + self.face_bits + 3 <= 63
        keys, faces = [], []
        while entries:
            face, coords, starts = entries.pop(0)
            key, _ = self.encode(coords)
            keys.append((((key << self.face_bits) | face) << 3 | starts) if packed else (key << 3 | starts))
            if not packed:
                faces.append(face)
        key = np.concatenate(keys) if keys else np.zeros(0, dtype=np.int64)
        del keys
        index = np.int32 if len(lo) < 2**31 else np.int64
        if packed:
            key.sort()
            starts = (key & 7).astype(np.uint8)
            key >>= 3
            self.face = (key & ((1 << self.face_bits) - 1)).astype(index)
            key >>= self.face_bits
        else:
            face = np.concatenate(faces)
            order = np.lexsort((face, key))
            key, self.face = key[order], face[order].astype(index)
            del order, face
            starts = (key & 7).astype(np.uint8)
            key >>= 3
        new = np.ones(key.size, dtype=bool)
        np.not_equal(key[1:], key[:-1], out=new[1:])
        self.cell_start = np.flatnonzero(new).astype(index)
        del new
        self.cell_key = key[self.cell_start]
        self.cell_end = np.append(self.cell_start[1:], index(key.size))
        self.high, self.low = self._words(key, self.face, starts)
        del key, starts
        self.members = members

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """The box around this slab's faces."""
        if self.members.size == 0:
            return np.full(3, np.inf), np.full(3, -np.inf)
        return self.lo[self.members].min(axis=0), self.hi[self.members].max(axis=0)

    def _entries(self, part: np.ndarray):
        """``(face, cell coordinates, start bits)`` of every cell in the slab the boxes of
        ``part`` overlap: at their level a face's box spans one or two cells per axis, so the
        cells are its first one plus each of the eight offsets in {0, 1}³ that it reaches
        (the start bits of an offset: the axes along which it is 0)."""
        first, last = _cells(self.lo[part], self.origin, self.size), _cells(self.hi[part], self.origin, self.size)
        wide = last > first                                 # (k, 3): reaches a second cell
        faces, coords, starts = [], [], []
        for dx in (0, 1):
            for dy in (0, 1):
                for dz in (0, 1):
                    mask = (first[:, 0] + dx >= self.x0) & (first[:, 0] + dx < self.x1)
                    if dx:
                        mask &= wide[:, 0]
                    if dy:
                        mask &= wide[:, 1]
                    if dz:
                        mask &= wide[:, 2]
                    rows = np.flatnonzero(mask)
                    faces.append(part[rows])
                    coords.append(first[rows] + np.array([dx, dy, dz]))
                    starts.append(np.full(rows.size, (dx == 0) + 2 * (dy == 0) + 4 * (dz == 0), dtype=np.int64))
        return np.concatenate(faces), np.concatenate(coords), np.concatenate(starts)

    def encode(self, coords: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The keys of cells ``(k, 3)``, and which of them this grid can hold (the others
        hold none of its faces)."""
        if self.axes is None:
            valid = np.all((coords >= 0) & (coords < (1 << np.array(self.bits))), axis=1)
            ranks = coords
        else:
            ranks = np.empty_like(coords)
            valid = np.ones(len(coords), dtype=bool)
            for a, axis in enumerate(self.axes):
                if not axis.size:
                    valid[:] = False
                    continue
                at = np.minimum(np.searchsorted(axis, coords[:, a]), axis.size - 1)
                valid &= axis[at] == coords[:, a]
                ranks[:, a] = at
        by, bz = self.bits[1], self.bits[2]
        ranks = np.where(valid[:, None], ranks, 0)
        return (ranks[:, 0] << (by + bz)) | (ranks[:, 1] << bz) | ranks[:, 2], valid

    def decode(self, key: np.ndarray) -> np.ndarray:
        """The cell coordinates ``(k, 3)`` of keys."""
        by, bz = self.bits[1], self.bits[2]
        ranks = np.stack([key >> (by + bz), (key >> bz) & ((1 << by) - 1), key & ((1 << bz) - 1)], axis=1)
        if self.axes is None:
            return ranks
        return np.stack([axis[ranks[:, a]] for a, axis in enumerate(self.axes)], axis=1)

    def _words(self, key: np.ndarray, faces: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The packed upper and lower words of the entries ``(cell key, face, start bits)``
        (module docstring)."""
        high = np.empty(key.size, dtype=np.uint64)
        low = np.empty(key.size, dtype=np.uint64)
        scale = 256.0 / self.size
        for at in range(0, key.size, PAIR_CHUNK):
            k = key[at:at + PAIR_CHUNK]
            face = faces[at:at + PAIR_CHUNK]
            box_lo, box_hi = self.lo[face], self.hi[face]
            h = starts[at:at + PAIR_CHUNK].astype(np.uint64) << START_SHIFT
            lw = h.copy()
            cells = self.decode(k)
            for axis in range(3):
                cell = cells[:, axis]
                # Quantised to 1/256 of the cell, a step of margin each way (the rounding of the
                # scaling never makes a quantised box smaller than the box), clipped to the cell.
                base = (cell * 256).astype(np.float64)
                q_lo = np.floor((box_lo[:, axis] - self.origin[axis]) * scale) - base - 1
                q_hi = np.floor((box_hi[:, axis] - self.origin[axis]) * scale) - base + 1
                q_lo = np.clip(q_lo, 0, 255, out=q_lo).astype(np.uint64)
                q_hi = np.clip(q_hi, 0, 255, out=q_hi).astype(np.uint64)
                h |= (q_hi << np.uint64(FIELD * axis)) | ((BYTE - q_lo) << np.uint64(FIELD * (axis + 3)))
                lw |= (q_lo << np.uint64(FIELD * axis)) | ((BYTE - q_hi) << np.uint64(FIELD * (axis + 3)))
            high[at:at + PAIR_CHUNK], low[at:at + PAIR_CHUNK] = h, lw
        return high, low

    def own_blocks(self) -> Blocks:
        """This level's pairs that share a cell (kept in their owner cell, boxes overlapping),
        a block of whole cells at a time: ``(faces of the block's entries, p, q)``."""
        cells = self.cell_start.size
        size = (self.cell_end - self.cell_start).astype(np.int64)
        # Candidate pairs up to each cell: blocks of about PAIR_CHUNK * 4 candidates (memory).
        reach = np.cumsum(size * (size - 1) // 2)
        first = 0
        while first < cells:
            done = int(reach[first - 1]) if first else 0
            last = int(np.searchsorted(reach, done + 4 * PAIR_CHUNK, side="right"))
            last = max(last, first + 1)
            lo, hi = int(self.cell_start[first]), int(self.cell_end[last - 1])
            high, low = self.high[lo:hi], self.low[lo:hi]
            members = self.face[lo:hi]
            pairs, waiting = [], 0
            for p, q in cell_pairs(self.cell_start[first:last] - lo, self.cell_end[first:last] - lo):
                pairs.append((p, q))
                waiting += p.size
                if waiting >= 4 * PAIR_CHUNK:       # a crowded cell comes in pieces (memory)
                    yield kept(members, high, low, pairs)
                    pairs, waiting = [], 0
            if pairs:
                yield kept(members, high, low, pairs)
            first = last

    def probe(self, queries: np.ndarray) -> Blocks:
        """Pairs of finer faces ``queries`` with this slab's faces in the cells they overlap."""
        who, coords, starts = self._entries(queries)
        key, inside = self.encode(coords)
        who, key = who[inside], key[inside]
        if key.size == 0 or self.cell_key.size == 0:
            return
        at = np.minimum(np.searchsorted(self.cell_key, key), self.cell_key.size - 1)
        hit = self.cell_key[at] == key
        who, at, key = who[hit], at[hit], key[hit]
        _, low = self._words(key, who, starts[inside][hit].astype(np.uint64))   # the probes' own words
        begin, size = self.cell_start[at], self.cell_end[at] - self.cell_start[at]
        for index, step in items(size):        # (probe, every entry of its cell)
            entry = begin[index] + step
            keep = meet(self.high[entry], low[index])
            if keep.any():
                i, j = who[index][keep], self.face[entry][keep]
                k = np.arange(i.size)
                yield np.concatenate([i, j]), k, k + i.size


def _slices(members: np.ndarray, step: int = PAIR_CHUNK) -> Iterator[np.ndarray]:
    for lo in range(0, members.size, step):
        yield members[lo:lo + step]


def _overlap(lo: np.ndarray, hi: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Whether the closed boxes ``i`` and ``j`` overlap, row by row."""
    a_lo, a_hi, b_lo, b_hi = lo[i], hi[i], lo[j], hi[j]
    keep = (a_lo[:, 0] <= b_hi[:, 0]) & (b_lo[:, 0] <= a_hi[:, 0])
    keep &= (a_lo[:, 1] <= b_hi[:, 1]) & (b_lo[:, 1] <= a_hi[:, 1])
    keep &= (a_lo[:, 2] <= b_hi[:, 2]) & (b_lo[:, 2] <= a_hi[:, 2])
    return keep & (i != j)
