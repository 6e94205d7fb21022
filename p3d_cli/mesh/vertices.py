"""Exact vertex ids of a triangle soup's corners: one sort of packed hash keys, confirmed exactly.

Every corner (``3 f + k``: corner ``k`` of face ``f``, file order) gets a 64-bit hash of its
coordinates (``closed.corner_hashes``); the hash's high bits and the corner index are packed
into one ``uint64`` key, so that a single in-place ``numpy.sort`` (no ``argsort``, no second
array) groups the corners by vertex and, within a vertex, by file order. The hash only chooses
the grouping: in a second pass every corner's coordinates are compared exactly with those of
its group's first corner, and a group that holds more than one point (a collision of the
truncated hashes: expected about ``m² / 2^(65 - b)`` times for ``m`` vertices) is split
exactly. So ids are equal exactly when coordinates are equal (``-0.0 == 0.0``), whatever the
hash does. Vertex ids are numbered in the order of the corners' full 64-bit hashes (as
``numpy.unique`` of the hashes numbers them), which fixes the order of problem samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.mesh.closed import _column_hashes, corner_hashes
from p3d_cli.mesh.columns import columns, origin_from_bounds
from p3d_cli.mesh.volume import SignedVolume
from p3d_cli.mesh.kernels import NotTaken, compiled, confirm_fans, key_buffer, sort

#: Corners handled per vectorised step of the passes over the sorted keys (cache-sized).
CHUNK = 1 << 16


@dataclass
class Corners:
    """Corners grouped by exact vertex.

    Attributes
    ----------
    ids : (3n,) int32 or int64
        Vertex id of corner ``3 f + k``.
    keys : (3n,) uint64
        Sorted packed keys: ``keys & mask`` is the corner index, grouped by vertex id.
    bits : int
        Bits of the corner index in ``keys``.
    first : (m + 1,) int32 or int64
        Vertex ``v``'s corners are at sorted positions ``first[v]:first[v + 1]``.
    points : (m, 3) float
        Coordinates of each vertex (as stored in the input, not widened).
    volume : float
        Signed volume of the soup's local sums (about the first block's bounding-box centre,
        each block summed as ``p3d props``' one-pass analysis sums it); a closed or bounding
        mesh's volume. An open mesh's adds its net boundary's terms (``volume_sums``).
    volume_sums : SignedVolume
        The accumulator behind ``volume``, for ``volume_sums.volume(extra)``.
    """

    ids: np.ndarray
    keys: np.ndarray
    bits: int
    first: np.ndarray
    points: np.ndarray
    volume: float
    volume_sums: SignedVolume | None = None

    @property
    def count(self) -> int:
        return int(self.first.size - 1)

    def corner(self, lo: int, hi: int) -> np.ndarray:
        """Corner indices at sorted positions ``lo:hi`` (int64)."""
        return (self.keys[lo:hi] & np.uint64((1 << self.bits) - 1)).astype(np.int64)

    def corner_at(self, positions: np.ndarray) -> np.ndarray:
        """Corner indices at the given sorted positions (int64)."""
        return (self.keys[positions] & np.uint64((1 << self.bits) - 1)).astype(np.int64)


def group_corners(blocks, n: int, on_block=None, hasher=None, where: str | None = None) -> Corners:
    """Exact vertex ids of the corners of ``n`` triangles read from ``blocks()``.

    Parameters
    ----------
    blocks : callable
        Returns an iterator over ``(k, 3, 3)`` float arrays, the triangles in file order;
        called twice (three times when a hash group must be split).
    n : int
        Number of triangles.
    on_block : callable, optional
        Called as ``on_block(first_face, cols, block)`` for every block of the first pass
        (``cols`` the ``(3, 3, k)`` float64 columns), for per-face work done in the same read.
    where : str, optional
        The input's name: when given, a NaN or infinite coordinate raises ``InputError``.
    hasher : callable, optional
        ``hasher(cols) -> (3, k) uint64`` corner hashes; default ``closed.corner_hashes``'
        (any function works: the groups are confirmed exactly).
    """
    bits = max(int(3 * n - 1).bit_length(), 1)
    keys, lo, hi, float32 = _hashed_keys(blocks, n, bits, on_block, hasher, where)
    sort(keys)  # radix, when compiled: the same order
    ids, first = _ids_from_sorted(keys, n, bits)
    # The origin ``p3d props`` sums about (the first block's bounding-box centre), so that both
    # commands report one number (docs/method.md, "Open and non-manifold meshes").
    points, volume, mixed = _confirm(blocks, ids, keys, first, bits,
                                     origin_from_bounds(lo, hi, float32) if n else np.zeros(3))
    if mixed.size:
        ids, first, points = _split_groups(blocks, keys, ids, first, points, bits, mixed)
    return Corners(ids, keys, bits, first, points, volume.volume(), volume)


def _hashed_keys(blocks, n: int, bits: int, on_block, hasher, where):
    """Pass 1: the packed keys ``(hash high bits) | corner index``, and the first block's
    bounds and dtype (the local origin's, as in ``p3d_cli.mesh.analysis``)."""
    keys = key_buffer(3 * n)            # ordinary pages: see kernels.key_buffer
    high = np.uint64(((1 << 64) - 1) ^ ((1 << bits) - 1))
    lo = hi = None
    float32 = False
    done = 0
    first_bounds = None
    for block in blocks():
        cols = columns(block)
        k = cols.shape[2]
        if k == 0:
            continue
        if done + k > n:
            count_error(where, n, f"more than {n}")
        float32 = np.asarray(block).dtype == np.float32
        block_lo, block_hi = block_bounds(cols, where, done)
        lo = block_lo if lo is None else np.minimum(lo, block_lo)
        hi = block_hi if hi is None else np.maximum(hi, block_hi)
        if first_bounds is None:
            first_bounds = (block_lo, block_hi, float32)
        if on_block is not None:
            on_block(done, cols, block)
        if hasher is None:
            h = _column_hashes(cols, np.empty((3, k), dtype=np.uint64))   # (slot, face)
        else:
            h = hasher(cols)
        out = keys[3 * done:3 * (done + k)].reshape(k, 3)
        np.bitwise_and(h.T, high, out=out)
        out |= np.arange(3 * done, 3 * (done + k), dtype=np.uint64).reshape(k, 3)
        done += k
    if done != n:
        count_error(where, n, str(done))
    if first_bounds is None:
        return keys, lo, hi, float32
    return (keys, *first_bounds)


def block_bounds(cols: np.ndarray, where: str | None, done: int) -> tuple[np.ndarray, np.ndarray]:
    """Lowest and highest coordinates of a block's ``(3, 3, k)`` columns; when ``where`` is
    given, a NaN or infinite coordinate raises ``InputError`` naming the face (``done``: the
    faces of earlier blocks)."""
    block_lo, block_hi = cols.min(axis=2).min(axis=0), cols.max(axis=2).max(axis=0)
    # min and max propagate NaN and show any infinity: a finite check for free.
    if where is not None and not (np.isfinite(block_lo).all() and np.isfinite(block_hi).all()):
        from p3d_cli.errors import InputError

        bad = int(np.flatnonzero(~np.isfinite(cols).all(axis=(0, 1)))[0])
        raise InputError(where, f"face {done + bad} has a NaN or infinite coordinate",
                         "repair or re-export the mesh")
    return block_lo, block_hi


def count_error(where: str | None, n: int, read: str):
    from p3d_cli.errors import FormatError

    raise FormatError(where or "<mesh>", f"expected {n} faces but read {read}",
                      "the file is truncated or corrupt; export it again")


def _ids_from_sorted(keys: np.ndarray, n: int, bits: int):
    """Vertex ids from the sorted keys, taking equal high bits for one vertex (confirmed later)."""
    ids = np.empty(3 * n, dtype=np.int32 if 3 * n < 2**31 else np.int64)
    starts = []
    shift, mask = np.uint64(bits), np.uint64((1 << bits) - 1)
    count, previous = 0, None
    for lo in range(0, keys.size, CHUNK):
        part = keys[lo:lo + CHUNK]
        prefix = part >> shift
        new = np.empty(part.size, dtype=bool)
        new[0] = previous is None or prefix[0] != previous
        np.not_equal(prefix[1:], prefix[:-1], out=new[1:])
        vid = np.cumsum(new, dtype=ids.dtype)
        vid += count - 1
        ids[(part & mask).astype(np.int64)] = vid
        starts.append((np.flatnonzero(new) + lo).astype(ids.dtype))
        count = int(vid[-1]) + 1
        previous = prefix[-1]
    first = np.concatenate(starts + [np.array([keys.size], dtype=ids.dtype)])
    return ids, first


def _confirm(blocks, ids, keys, first, bits, origin):
    """Pass 2: each corner against its vertex's first corner, exactly; the volume sums.

    Returns the vertex coordinates, the volume and the ids of vertices whose corners are not
    all at one point (hash groups to split).
    """
    mask = np.uint64((1 << bits) - 1)
    m = first.size - 1
    is_first = np.zeros(keys.size, dtype=bool)     # a sequential mask, not a gather per corner
    is_first[(keys[first[:-1]] & mask).astype(np.int64)] = True
    fast = compiled()
    if fast is not None:
        found = _confirm_compiled(blocks, ids, is_first, m, origin)
        if found is not None:
            return found
    # One array per axis, so that each comparison is a 1-D gather (float64: the widened,
    # exact coordinates, which compare equal exactly when the stored ones do).
    axes = None
    bad = []
    volume = SignedVolume(origin, block=None)
    done = 0
    for block in blocks():
        cols = columns(block)                       # (slot, axis, face), contiguous
        k = cols.shape[2]
        if k == 0:
            continue
        if axes is None:  # float32 input: float32 coordinates (exact), half the memory
            axes = np.zeros((3, m), dtype=np.asarray(block).dtype)
        own_block = is_first[3 * done:3 * (done + k)].reshape(k, 3)
        vid = ids[3 * done:3 * (done + k)].reshape(k, 3).astype(np.int64)
        # A vertex's first corner is its earliest in file order: in this block or before.
        # So set the first corners' coordinates of the whole block, then compare every corner.
        for slot in range(3):
            v = vid[:, slot]
            own = own_block[:, slot]
            for axis in range(3):
                axes[axis, v[own]] = cols[slot, axis, own]
        for slot in range(3):
            v = vid[:, slot]
            differ = axes[0, v] != cols[slot, 0]
            differ |= axes[1, v] != cols[slot, 1]
            differ |= axes[2, v] != cols[slot, 2]
            if differ.any():
                bad.append(v[differ])
        volume.add_columns(cols)
        done += k
    points = np.ascontiguousarray(axes.T) if axes is not None else np.zeros((m, 3))
    mixed = np.unique(np.concatenate(bad)) if bad else np.zeros(0, dtype=np.int64)
    return points, volume, mixed


def _confirm_compiled(blocks, ids, is_first, m: int, origin):
    """``_confirm`` by the compiled kernels, when every group is one point (the usual case):
    ``kernels.confirm_fans``'s comparisons, block by block, with the volume's sums (the bits
    ``SignedVolume.add_columns`` gives, as ``paired._keyed_pass`` sums them). None when some
    group holds several points or a block is not one the kernels read: the numpy code then
    finds which."""
    volume = SignedVolume(origin, block=None)
    try:
        points = confirm_fans(blocks, ids, m, is_first, volume)
    except NotTaken:
        return None
    return None if points is None else (points, volume, np.zeros(0, dtype=np.int64))


def _split_groups(blocks, keys, ids, first, points, bits, mixed):
    """Split hash groups holding several points into exact vertices, renumbering all ids.

    The corners of the ``mixed`` vertex ids are regrouped by their exact coordinates, ordered
    by full hash, then coordinates (as ``numpy.unique`` of the full hashes would number them),
    and the sorted keys of each such group are reordered to stay grouped by vertex.
    """
    mask = np.uint64((1 << bits) - 1)
    positions = np.concatenate([np.arange(a, b) for a, b in
                                zip(first[mixed].tolist(), first[mixed + 1].tolist())])
    corners = (keys[positions] & mask).astype(np.int64)
    coords = corner_coords(blocks, corners)
    full = corner_hashes(coords)
    owner = ids[corners].astype(np.int64)
    order = np.lexsort((corners, coords[:, 2], coords[:, 1], coords[:, 0], full, owner))
    corners, owner, coords = corners[order], owner[order], coords[order]
    new = np.ones(len(corners), dtype=bool)
    new[1:] = (owner[1:] != owner[:-1]) | (coords[1:] != coords[:-1]).any(axis=1)
    owner_start = np.ones(len(corners), dtype=bool)
    owner_start[1:] = owner[1:] != owner[:-1]
    count_new = np.cumsum(new)
    rank = count_new - count_new[np.flatnonzero(owner_start)][np.cumsum(owner_start) - 1]
    extra = np.zeros(first.size - 1, dtype=np.int64)
    np.add.at(extra, owner, new)                        # sub-vertices per mixed vertex
    extra[mixed] -= 1
    base = np.arange(first.size - 1, dtype=np.int64)
    base[1:] += np.cumsum(extra)[:-1]
    new_ids = base[ids]
    new_ids[corners] = base[owner] + rank
    keys[positions] = keys[positions][order]            # same positions, grouped by new id
    sorted_ids = new_ids[(keys & mask).astype(np.int64)]
    starts = np.flatnonzero(np.concatenate(([True], sorted_ids[1:] != sorted_ids[:-1])))
    count = int(base[-1] + extra[-1] + 1)
    new_points = np.empty((count, 3), dtype=points.dtype)
    keep = np.ones(first.size - 1, dtype=bool)
    keep[mixed] = False
    new_points[base[keep]] = points[keep]
    new_points[(base[owner] + rank)[new]] = coords[new]
    return (new_ids.astype(ids.dtype), np.append(starts, len(keys)).astype(np.int64), new_points)


def corner_coords(blocks, corners: np.ndarray) -> np.ndarray:
    """Float64 coordinates of the given corner indices (one more pass over the blocks)."""
    out = np.empty((len(corners), 3))
    order = np.argsort(corners)
    wanted = corners[order]
    done = 0
    for block in blocks():
        flat = np.asarray(block).reshape(-1, 3)
        a, b = np.searchsorted(wanted, [done, done + len(flat)])
        out[order[a:b]] = flat[wanted[a:b] - done]
        done += len(flat)
    return out + 0.0
