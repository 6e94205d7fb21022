"""Pass 1 of ``p3d check``'s fast path (``p3d_cli.mesh.paired``): the side keys.

For every side ``3 f + k`` the key ``(edge hash, low bits cleared) | direction << bits | side``,
with the exact zero-area faces and the signed volume of the same blocks about the same origin
as ``vertices.group_corners`` (so the same bits), and the balance of the edge keys: keys of
sides used once each way cancel in ``sum(forward) - sum(backward)`` (mod 2^64), so a balance
that does not cancel proves some edge is not, before any sort.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.closed import _GOLDEN, _column_hashes
from p3d_cli.mesh.columns import columns, origin_from_bounds
from p3d_cli.mesh.faces import zero_area_faces, zero_area_faces_compiled
from p3d_cli.mesh.kernels import Buckets, compiled, key_buffer
from p3d_cli.mesh.kernels import takes as kernel_takes
from p3d_cli.mesh.splitmix import mix
from p3d_cli.mesh.vertices import block_bounds, count_error
from p3d_cli.mesh.volume import SignedVolume

_ONE = np.uint64(1)


def keyed_pass(blocks, n: int, bits: int, where, hasher, balanced: bool = True):
    """Pass 1: the side keys ``edge hash | direction << bits | side``, zero-area faces and the
    volume's sums (``SignedVolume``); None as soon as a side's two ends hash alike (the general
    path's case), or when the edge keys do not balance and ``balanced`` asks them to (a mesh
    with boundary edges does not balance)."""
    low = np.uint64((1 << (bits + 1)) - 1)
    shift = np.uint64(bits)
    zero: list[np.ndarray] = []
    volume = None
    done = balance = 0
    fast = compiled() if hasher is None else None
    buckets = None
    if fast is not None and 3 * n >= 1 << 16:
        # The compiled pass deals the keys to buckets by their top bits (the edge hash): the
        # sort then needs no pass over all of them (p3d_cli.mesh.kernels.Buckets).
        buckets = Buckets(3 * n)
        keys = None
    else:
        keys = key_buffer(3 * n)        # ordinary pages: see kernels.key_buffer
    for block in blocks():
        if buckets is not None and volume is not None and kernel_takes(block):
            # After the first block (whose bounds place the origin), the compiled pass reads
            # the block's own records: no float64 columns. A block with a NaN or an infinity
            # takes the road below, which names the face.
            k = len(block)
            if k == 0:
                continue
            if done + k > n:
                count_error(where, n, f"more than {n}")
            _, finite, totals, magnitude, _, _ = fast.block(block, *volume.origin, None, 0)
            if finite:
                zero.append(zero_area_faces_compiled(block, fast) + done)
                degenerate, forward_sum, total, written = fast.paired_keys(
                    block, bits, done, buckets.keys, buckets.fill, buckets.cap, buckets.shift)
                if degenerate or written < 0:
                    return None         # a side that may bound nothing, or crowded keys: the general path
                balance += 2 * forward_sum - total
                volume.add_sums(totals[0], magnitude, k)
                done += k
                continue
        cols = columns(block)
        k = cols.shape[2]
        if k == 0:
            continue
        if done + k > n:
            count_error(where, n, f"more than {n}")
        lo, hi = block_bounds(cols, where, done)
        if volume is None:
            # The origin ``p3d props`` sums about: the first block's bounding-box centre.
            volume = SignedVolume(origin_from_bounds(lo, hi, np.asarray(block).dtype == np.float32),
                                  block=None)
        zero.append(zero_area_faces(cols) + done)
        if buckets is not None and kernel_takes(block):
            degenerate, forward_sum, total, written = fast.paired_keys(
                block, bits, done, buckets.keys, buckets.fill, buckets.cap, buckets.shift)
            if degenerate or written < 0:
                return None             # a side that may bound nothing, or crowded keys: the general path
            balance += 2 * forward_sum - total
            _, _, totals, magnitude, _, _ = fast.block(block, *volume.origin, None, 0)
            volume.add_sums(totals[0], magnitude, k)
            done += k
            continue
        scratch = np.empty((3, k), dtype=np.uint64)
        key = np.empty((3, k), dtype=np.uint64) if keys is None else keys[3 * done:3 * (done + k)].reshape(3, k)
        if fast is not None:
            # The compiled side keys are (edge hash & ~1) | direction: the same hash bits.
            if fast.side_keys(cols.transpose(2, 0, 1), key.reshape(-1), scratch.view(np.uint8)[0, :3 * k]):
                return None             # a side that may bound nothing: the general path
            forward = key & _ONE
            key &= ~low
        else:
            h = _column_hashes(cols, scratch) if hasher is None else np.asarray(hasher(cols), np.uint64)
            start, end = h, h[[1, 2, 0]]
            if (start == end).any():
                return None             # a side that may bound nothing: the general path
            forward = np.less(start, end).view(np.uint8).astype(np.uint64)
            # Computed in its place in ``keys``: where a key sits does not matter (they are
            # sorted), so the block's keys are stored in (slot, face) order and carry their side.
            np.minimum(start, end, out=key)
            key *= _GOLDEN
            key += np.maximum(start, end, out=end)
            mix(key, scratch)
            key &= ~low
        # Edge keys used once each way cancel in (sum forward - sum backward) mod 2^64; a
        # sum that does not cancel proves some edge is not, before any sort.
        balance += 2 * int(np.multiply(key, forward, out=scratch).sum()) - int(key.sum())
        forward <<= shift
        key |= forward
        key += _side_numbers(k)
        key += np.uint64(3 * done)
        if buckets is not None:
            buckets.add(key.reshape(-1))
            if buckets.overflow:
                return None
        if fast is not None:
            # The compiled sums about the same origin: row 0 and the magnitudes are the bits
            # SignedVolume would sum (p3d_cli.mesh.kernels).
            _, _, totals, magnitude, _, _ = fast.block(cols.transpose(2, 0, 1), *volume.origin, None, 0)
            volume.add_sums(totals[0], magnitude, k)
        else:
            volume.add_columns(cols)
        done += k
    if done != n:
        count_error(where, n, str(done))
    if balanced and balance % 2**64:
        return None
    assert volume is not None
    if buckets is not None:
        keys = buckets.sorted_keys()
        del buckets
        return keys, True, np.concatenate(zero), volume
    return keys, False, np.concatenate(zero), volume


_SIDES: list[np.ndarray] = []


def _side_numbers(k: int) -> np.ndarray:
    """``3 j + slot`` as ``(3, k)`` uint64 (slot, face): side numbers of a block's faces."""
    if k > 1 << 16:                     # large blocks: not kept
        return 3 * np.arange(k, dtype=np.uint64) + np.arange(3, dtype=np.uint64)[:, None]
    if not _SIDES or _SIDES[0].shape[1] < k:
        _SIDES[:] = [(3 * np.arange(max(k, 1 << 14), dtype=np.uint64)
                      + np.arange(3, dtype=np.uint64)[:, None])]
    return _SIDES[0][:, :k]
