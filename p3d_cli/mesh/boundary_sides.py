"""The net boundary's edges and sides: which edges of a triangle soup are used unequally often
in their two directions (``Unbalanced``, from the sorted side keys of ``p3d_cli.mesh.closed``),
and their sides, picked from the file block by block for the boundary terms
(``p3d_cli.mesh.boundary``): ``unbalanced_sides`` from one more pass given the edges,
``sides_of_prints`` for ``p3d props``' road by prints (the edges and their sides from one pass,
``p3d_cli.mesh.analysis``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.closed import column_edge_keys, key_groups, side_keys
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.kernels import compiled, key_balance, sort, takes

#: Sides handled per vectorised step of the boundary terms: the temporaries (~30 rows of this
#: many floats) stay in cache; 2**15 was 1.7x slower, 2**13 the same (a 1M-face soup).
SIDE_BLOCK = 1 << 14


@dataclass(frozen=True)
class Unbalanced:
    """The edges of sorted side keys whose two directions are not used equally often.

    Attributes
    ----------
    ids : (d,) uint64, sorted
        Their edge ids (``key >> 1``). Equal exact edges have equal keys, so an edge whose key
        group is balanced cancels unless two different edges' 64-bit keys collided (the risk
        ``closed`` already takes for its pairs).
    edges : int
        The net boundary's size: ``|forward - backward|`` summed over their key groups.
    sides : int
        Sides in their key groups.
    total : int
        All the sides.
    """

    ids: np.ndarray
    edges: int
    sides: int
    total: int

    @property
    def most(self) -> bool:
        """Whether most sides are in unbalanced groups (a soup): then every side is used."""
        return 2 * self.sides > self.total


def unbalanced_groups(keys: np.ndarray) -> Unbalanced:
    """``Unbalanced`` of sorted side ``keys``, in one scan."""
    kernels = compiled()
    if kernels is not None and keys.flags.c_contiguous:
        ids, size, sides, _ = kernels.groups(keys)
        return Unbalanced(np.frombuffer(ids, dtype=np.uint64).copy(), size, sides, int(keys.size))
    found, size, sides = [], 0, 0
    for edge, counts, forward in key_groups(keys):
        net = 2 * forward.astype(np.int64) - counts
        odd = net != 0
        found.append(edge[odd])
        size += int(np.abs(net[odd]).sum())
        sides += int(counts[odd].sum())
    return Unbalanced(np.concatenate(found) if found else keys[:0], size, sides, int(keys.size))


def unbalanced_of(source_blocks) -> Unbalanced:
    """``unbalanced_groups`` of the triangles read once from ``source_blocks()`` (a callable)."""
    keys = [column_edge_keys(columns(block)) for block in source_blocks()]
    flat = np.concatenate(keys) if keys else np.zeros(0, dtype=np.uint64)
    sort(flat)  # radix, when compiled: the same order
    return unbalanced_groups(flat)


def unbalanced_sides(source_blocks, unbalanced: np.ndarray, every: bool = False):
    """Every side (as ``(3, k)`` start and end columns, ``-0.0`` read as ``0.0``) whose edge
    is in ``unbalanced`` (or every side with two distinct ends, if ``every``), ``SIDE_BLOCK``
    at most at a time, from one more pass.

    These sides are the net boundary plus sides that cancel in pairs (``u→v`` and ``v→u``):
    as a chain they are the net boundary, a cycle, which is all ``boundary_terms`` needs, and
    the terms of a pair cancel (exactly: ``Locals`` computes ``v→u``'s as the negated bits of
    ``u→v``'s, but for the order of the low parts' sum, within its bound). Membership is a
    binary search in the sorted ids, not ``numpy.isin`` (which hashes all the ids again for
    every block); a soup, whose sides are nearly all unbalanced, skips it (``every``).
    """
    ids = np.sort(unbalanced)
    if ids.size == 0:
        return
    members = Members(ids)
    kernels = compiled()
    out = np.empty((0, 6))
    index = members.starts() if kernels is not None and not every else None
    for block in source_blocks:
        if kernels is not None and not every and takes(block):
            # The same sides in the same order, picked by the compiled kernel from the
            # block's own records (no float64 copy, no keys array).
            if out.shape[0] < 3 * len(block):
                out = np.empty((3 * len(block), 6))
            sides = out[:kernels.pick_sides(block, ids, members.bits, int(members.shift), *index, out)]
            yield from _chunks(sides[:, :3], sides[:, 3:])
            continue
        cols = columns(block)
        if cols.shape[2] == 0:
            continue
        keys, keep = side_keys(cols)
        if not every:
            hit = members(keys >> np.uint64(1))
            if not hit.any():
                continue
            # Only the hit sides' corners, in the keys' (slot, face) order: side i of the kept
            # sides is slot i // k, face i % k (a few per cent of the sides on a holed mesh).
            position = np.flatnonzero(hit)
            if keep is not None:
                position = np.flatnonzero(keep.reshape(-1))[position]
            slot, face = np.divmod(position, cols.shape[2])
            start = cols[slot, :, face] + 0.0
            end = cols[(slot + 1) % 3, :, face] + 0.0
            yield from _chunks(start, end)
            continue
        corners = np.moveaxis(cols, 1, 2) + 0.0            # (slot, face, axis), as keys
        start, end = corners, corners[[1, 2, 0]]
        if keep is not None:
            start, end = start[keep], end[keep]
        yield from _chunks(start.reshape(-1, 3), end.reshape(-1, 3))


def _chunks(start: np.ndarray, end: np.ndarray):
    """Sides given as ``(m, 3)`` start and end points, as ``(3, k)`` columns, ``SIDE_BLOCK`` at
    most at a time (each a contiguous copy)."""
    for first in range(0, start.shape[0], SIDE_BLOCK):
        at = slice(first, first + SIDE_BLOCK)
        yield np.ascontiguousarray(start[at].T), np.ascontiguousarray(end[at].T)


class Members:
    """``numpy.isin(edge, ids)`` for sorted ``ids`` of edges (63-bit hashes): a few equality
    tests when there are a few ids (a mesh with a hole or two: 12x faster than a binary
    search), else a table of the ids' top bits first, which turns most edges away with one
    lookup, and a binary search for the rest. (A binary search of every edge took 0.5 s of a
    1M-face mesh with 1 % of its faces missing, 30,000 ids: three times the whole analysis.)"""

    def __init__(self, ids: np.ndarray, width: int = 63) -> None:
        self.ids = ids
        #: The ids' width in bits: 63 for edge ids, more or less for other ids (print ids).
        self.width = width
        # About 32 slots an id (at most 2^24): 97 % of the other edges miss the table.
        bits = min(24, max(8, (32 * ids.size).bit_length()))
        self.shift = np.uint64(width - bits)
        self.table = np.zeros(1 << bits, dtype=bool)
        self.table[(ids >> self.shift).astype(np.intp)] = True
        #: The table packed 8 slots a byte, for the compiled ``pick_sides``.
        self.bits = np.packbits(self.table, bitorder="little")

    def starts(self) -> tuple[np.ndarray, int]:
        """An index of the ids by their top bits, for the compiled ``pick_sides``: ``starts[j]``
        is the first id at or above ``j << shift``, about one id a slot; and ``shift``."""
        bits = max(1, int(self.ids.size).bit_length())
        shift = self.width - bits
        bounds = np.arange((1 << bits) + 1, dtype=np.uint64) << np.uint64(shift)
        return np.searchsorted(self.ids, bounds).astype(np.int64), shift

    def __call__(self, edge: np.ndarray) -> np.ndarray:
        ids = self.ids
        if ids.size <= 16:
            hit = edge == ids[0]
            for value in ids[1:]:
                hit |= edge == value
            return hit
        hit = self.table[(edge >> self.shift).astype(np.intp)]
        maybe = np.flatnonzero(hit)
        candidates = edge[maybe]
        at = np.minimum(np.searchsorted(ids, candidates), ids.size - 1)
        hit[maybe] = ids[at] == candidates
        return hit


def sides_of_prints(source_blocks, prints: np.ndarray, low: int, count: int, balance: int,
                    total: int) -> tuple[Unbalanced, list[np.ndarray]] | None:
    """``unbalanced_groups`` of every side's key and ``unbalanced_sides``' sides, block by
    block, from one pass that picks the sides whose print id (``key >> low``) is in ``prints``
    (the compiled ``print_groups``' answers: ``count`` sides) with their keys.

    Every edge's sides share a print id, so the picked sides hold whole edge groups; their keys
    sorted give the unbalanced edges among them exactly. Those are all the mesh's when the
    balance of the picked sides, ``Σ ±mix(key | 1)`` (+ forward, - backward) mod 2**64, is the
    whole mesh's ``balance``: an unbalanced edge left out (two of them cancelling in one print
    group) would be missing from it but for a 64-bit coincidence, as in the closed test
    (``p3d_cli.mesh.kernels.ForwardBuckets``). Returns None, for the caller's other road, when it
    is not, when no edge is unbalanced, or when a block is not one the kernels read.

    Returns
    -------
    unbalanced : Unbalanced
        As ``unbalanced_groups`` of every side's key (``total`` sides).
    sides : list of (m, 6) float64
        Each block's sides whose edge is unbalanced, as the compiled ``unbalanced_sides`` picks
        them (start, end; the same order).
    """
    kernels = compiled()
    if kernels is None or prints.size == 0:
        return None
    members = Members(prints, 64 - low)
    index = members.starts()
    picked: list[np.ndarray] = []
    keys: list[np.ndarray] = []
    out = np.empty((0, 6))
    made = np.empty(0, dtype=np.uint64)
    found = 0
    for block in source_blocks:
        if not takes(block):
            return None
        if out.shape[0] < 3 * len(block):
            out, made = np.empty((3 * len(block), 6)), np.empty(3 * len(block), dtype=np.uint64)
        n = kernels.pick_sides(block, prints, members.bits, int(members.shift), *index, out, low, made)
        found += n
        if found > count:
            return None
        picked.append(out[:n].copy())
        keys.append(made[:n].copy())
    every = np.concatenate(keys) if keys else np.zeros(0, dtype=np.uint64)
    if every.size != count:
        return None
    if key_balance(every) != balance:
        return None
    ordered = every.copy()
    sort(ordered)
    ids, size, sides, doubtful = kernels.groups(ordered)
    if doubtful is not None or not ids:
        return None
    unbalanced = Unbalanced(np.frombuffer(ids, dtype=np.uint64).copy(), size, sides, total)
    if sides == count:                      # every picked side is on an unbalanced edge
        return unbalanced, picked
    hit = Members(unbalanced.ids)(every >> np.uint64(1))
    ends = np.cumsum([k.size for k in keys])
    return unbalanced, [p[h] for p, h in zip(picked, np.split(hit, ends[:-1]))]


def block_sides(picked: list[np.ndarray]):
    """``unbalanced_sides``' chunks of sides already picked block by block (``sides_of_prints``)."""
    for sides in picked:
        yield from _chunks(sides[:, :3], sides[:, 3:])
