"""The key groups of a mesh whose first pass did not prove it closed (``p3d_cli.mesh.analysis``):
which edges its sides use unequally often in the two directions (``Unbalanced``), which are
doubtful (used twice or more each way), and, where it comes for free, the net boundary's sides.

``open_groups`` takes the first pass's forward keys (``p3d_cli.mesh.kernels.ForwardBuckets``):
by the backward sides' prints and one more pass that also picks the sides (``printed_groups``),
else by the backward keys dealt in one more pass (the kernel's ``backward_block`` and
``split_groups``); ``all_keys`` makes every key again where the buckets overflowed.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from p3d_cli.io.source import MeshSource
from p3d_cli.mesh.boundary_sides import Unbalanced, sides_of_prints
from p3d_cli.mesh.closed import column_edge_keys
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.kernels import Buckets, ForwardBuckets, key_buffer, takes


def all_keys(source: MeshSource, fast, indexed: bool) -> tuple[np.ndarray, bool]:
    """Every side's edge key, sorted when the second flag says so: one more pass over the
    file (the compiled keys alone where it takes the blocks), for a mesh that the forward keys
    did not prove closed. Its coordinates are finite: the first pass refused any other."""
    buckets = Buckets(3 * source.face_count)
    item: Any
    for item in (source.index_blocks() if indexed else source.read_blocks()):
        if buckets.overflow:
            break
        if indexed or takes(item):
            if fast.keys_block(item, buckets.keys, buckets.fill, buckets.cap, buckets.shift) < 0:
                buckets.overflow = True
            continue
        buckets.add(column_edge_keys(columns(item)))
    if buckets.overflow:                            # keys crowding one bucket: made again in order
        del buckets
        return keys_in_order(source), False
    return buckets.sorted_keys(), True


def open_groups(source: MeshSource, fast, forward: ForwardBuckets,
                indexed: bool) -> tuple[Unbalanced, np.ndarray, bool, list | None] | None:
    """``unbalanced_groups`` and ``doubtful_edges`` of every side's key, whether they all pair
    up, and the net boundary's sides when they were picked on the way (else None), for a mesh
    the forward keys did not prove closed.

    First by the backward sides' prints (``printed_groups``); where they prove nothing, one
    more pass deals the other half of the keys (``backward_block``) to buckets beside the
    forward ones, and the kernel scans the two together bucket by bucket (``split_groups``),
    without making the forward keys again or moving the keys together. None when a bucket
    overflows (the caller then makes every key in order)."""
    if forward.whole:
        found = printed_groups(source, fast, forward)
        if found is not None:
            return found
    backward = Buckets.like(forward)
    backward.populate(forward.backward)
    item: Any
    for item in (source.index_blocks() if indexed else source.read_blocks()):
        if indexed or takes(item):
            if fast.backward_block(item, backward.keys, backward.fill, backward.cap, backward.shift) < 0:
                return None
            continue
        block_keys = column_edge_keys(columns(item))
        backward.add(block_keys[(block_keys & np.uint64(1)) == 0])
        if backward.overflow:
            return None
    ids, size, sides, doubtful = fast.split_groups(forward.keys, forward.fill, backward.keys, backward.fill,
                                                   forward.cap, forward.shift)
    total = int(forward.fill.sum() + backward.fill.sum())
    unbalanced = Unbalanced(np.frombuffer(ids, dtype=np.uint64).copy(), size, sides, total)
    if doubtful is None:
        return unbalanced, np.zeros(0, dtype=np.uint64), False, None
    return unbalanced, np.frombuffer(doubtful, dtype=np.uint64).copy(), total > 0 and not doubtful, None


#: The open road by prints takes meshes whose unbalanced print groups hold at most this share
#: of the sides. Their sides are kept while the pass runs, 56 bytes each: at most 1.75 bytes a
#: side of the mesh, less than the 4 the road by every key's backward keys take (8 bytes for
#: each of half the sides), so the road never needs more memory than that one.
PRINTED_SHARE = 1 / 32


def printed_groups(source: MeshSource, fast,
                   forward: ForwardBuckets) -> tuple[Unbalanced, np.ndarray, bool, list] | None:
    """``open_groups``' answers for an open mesh from the first pass's backward prints and
    one more pass, which also picks the net boundary's sides (no pass of backward keys, none
    to pick the sides after): the kernel groups the forward keys and the backward prints by
    print id (``print_groups``), and ``sides_of_prints`` picks the sides of the unbalanced
    print groups, finds the unbalanced edges among them from their keys and checks them
    against the whole mesh's balance. None, for the road by backward keys, when the prints
    prove nothing (no unbalanced print group, too many sides in them, or a check that fails)."""
    prints, _, count, doubtful = fast.print_groups(forward.keys, forward.fill, forward.prints, forward.print_fill,
                                                   forward.cap, forward.shift)
    total = int(forward.fill.sum()) + forward.backward
    if doubtful is not None or not prints or count > PRINTED_SHARE * total:
        return None
    found = sides_of_prints(source.read_blocks(), np.frombuffer(prints, dtype=np.uint64).copy(),
                            forward.shift - 32, count, forward.balance, total)
    if found is None:
        return None
    unbalanced, picked = found
    return unbalanced, np.zeros(0, dtype=np.uint64), False, picked


def keys_in_order(source: MeshSource) -> np.ndarray:
    """The edge keys of every block, one after the other (a second pass over the file)."""
    keys = key_buffer(3 * source.face_count)
    filled = 0
    for block in source.read_blocks():
        block_keys = column_edge_keys(columns(block))
        keys[filled:filled + block_keys.size] = block_keys
        filled += block_keys.size
    return keys[:filled]
