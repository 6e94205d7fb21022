"""Pairs within the broad phase's cells (``p3d_cli.mesh.broadphase``): every pair of a cell's
entries, the cells of one size at once, and their test on quantised boxes packed in words.

The words: six 9-bit fields, 8 data bits and a guard bit each, ``H = [hx, hy, hz, 255-lx,
255-ly, 255-lz]`` and ``L = [lx, ly, lz, 255-hx, 255-hy, 255-hz]`` of boxes quantised to 1/256
of their cell, and three start bits above them (``START_SHIFT``). Boxes i and j overlap along
every axis exactly when every field of ``H_j`` is at least the one of ``L_i``: in
``(H_j | GUARD) - L_i`` a field keeps its guard bit exactly when it did not borrow, and no
borrow crosses a field (each field of the difference is at least 1). H. S. Warren, *Hacker's
Delight*, 2nd ed., 2012, ch. 2 (SIMD within a register).
"""

from __future__ import annotations

from typing import Iterator

import numpy as np

#: Candidate pairs handled per vectorised step (the temporaries stay in cache).
PAIR_CHUNK = 1 << 16
FIELD = 9
DATA = np.uint64(sum(0xFF << (FIELD * k) for k in range(6)))
GUARD = np.uint64(sum(0x100 << (FIELD * k) for k in range(6)))
START_SHIFT = np.uint64(6 * FIELD)
SEVEN = np.uint64(7)
BYTE = np.uint64(255)


def kept(members, high, low, pairs):
    """``(members, p, q)`` of the candidate pairs whose quantised boxes meet in their owner cell."""
    p = np.concatenate([x for x, _ in pairs]) if len(pairs) > 1 else pairs[0][0]
    q = np.concatenate([y for _, y in pairs]) if len(pairs) > 1 else pairs[0][1]
    keep = np.flatnonzero(meet(np.take(high, q), np.take(low, p)))
    return members, np.take(p, keep), np.take(q, keep)


def meet(high: np.ndarray, low: np.ndarray) -> np.ndarray:
    """Whether entries with upper words ``high`` and lower words ``low`` (of the other box)
    overlap in every quantised field and are owned by their cell (start bits make 7)."""
    fields = ((high | GUARD) - (low & DATA)) & GUARD
    return (fields == GUARD) & ((((high | low) >> START_SHIFT) & SEVEN) == SEVEN)


def items(counts: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
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


#: Upper-triangle index pairs of an m x m table, by m (the pairs within a cell of m entries).
_TRIANGLES: dict[int, np.ndarray] = {}
#: Cells with more entries than this get their pairs a row at a time (bounded memory).
_BIG_CELL = 256


def _triangle(m: int) -> np.ndarray:
    pairs = _TRIANGLES.get(m)
    if pairs is None:
        a, b = np.triu_indices(m, 1)
        pairs = np.stack([a, b]).astype(np.int32)
        if m <= _BIG_CELL:
            _TRIANGLES[m] = pairs
    return pairs


def cell_pairs(starts: np.ndarray, ends: np.ndarray) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """Every pair of positions within each cell ``starts[c]:ends[c]``: the cells of one size
    ``m`` at once, from the ``m x m`` upper triangle (no per-pair index arithmetic)."""
    size = (ends - starts).astype(np.int64)
    present = np.bincount(size)                         # the sizes that occur (no sort)
    order = np.argsort(size, kind="stable") if size.size else size
    ranges = np.cumsum(present)
    for m in np.flatnonzero(present[2:]).tolist():
        m += 2
        first = starts[order[ranges[m] - present[m]:ranges[m]]].astype(np.int32)
        if m <= _BIG_CELL:
            a, b = _triangle(m)
            yield (first[:, None] + a).ravel(), (first[:, None] + b).ravel()
        else:
            for f in first.tolist():
                # Rows of the triangle, as many as make about PAIR_CHUNK pairs at a time.
                row = 0
                while row < m - 1:
                    rows = max(1, min(m - 1 - row, PAIR_CHUNK // (m - row)))
                    lead = np.arange(row, row + rows)
                    count = m - 1 - lead                  # partners after each row's entry
                    a = np.repeat(lead, count)
                    b = np.arange(a.size) - np.repeat(np.cumsum(count) - count, count)
                    yield (f + a).astype(np.int32), (f + a + 1 + b).astype(np.int32)
                    row += rows
