"""One pass over a mesh's triangle blocks: bounds, moments and the closed test together.

The integrals need no vertex merging or repair, so none is done: each block is checked for
finite coordinates, widened to float64, summed about a local origin, hashed for the closed
test and dropped. A streamed binary STL is therefore never held in memory whole.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from p3d_cli.errors import FormatError, InputError, RangeError
from p3d_cli.io.source import MeshSource
from p3d_cli.mesh.boundary import boundary_terms
from p3d_cli.mesh.boundary_sides import Unbalanced, unbalanced_groups
from p3d_cli.mesh.closed import column_edge_keys, doubtful_edges, keys_pair_up, sides_pair_up_exactly
from p3d_cli.mesh.columns import columns, local_origin, origin_from_bounds
from p3d_cli.mesh.integrals import MomentSums, tetrahedron_sums
from p3d_cli.mesh.open_groups import all_keys, open_groups
from p3d_cli.mesh.kernels import ForwardBuckets, compiled, key_buffer
from p3d_cli.mesh.kernels import takes as kernel_takes
from p3d_cli.results import Bounds, Moments


@dataclass(frozen=True)
class MeshAnalysis:
    """What one pass over a mesh found.

    Attributes
    ----------
    moments : Moments
    bounds : Bounds
    closed : bool or None
        None for volume meshes, where it does not apply.
    face_count : int
    inverted_tetrahedra : int
        Tetrahedra of a volume mesh listed with negative orientation (counted positive).
    bounding : bool or None
        Every directed edge is matched by as many uses in the opposite direction (the net
        boundary is empty, ``p3d_cli.mesh.boundary``): true for closed meshes and for
        non-manifold ones that still bound a region. None where the closed test was not run.
    boundary_edges : int
        Directed edges of the net boundary, counted with multiplicity.
    scale_exponent : int
        ``moments`` are those of the mesh scaled by ``2**scale_exponent`` about the world
        origin (``analyze(rescale=True)``; 0 unless the part is far outside float64's
        comfortable range).
    """

    moments: Moments
    bounds: Bounds
    closed: bool | None
    face_count: int
    inverted_tetrahedra: int = 0
    bounding: bool | None = None
    boundary_edges: int = 0
    scale_exponent: int = 0


#: Parts whose size lies outside [2**-RESCALE_BEYOND, 2**RESCALE_BEYOND] are integrated scaled
#: by a power of two (``analyze(rescale=True)``): their second moments (size⁵) would reach
#: float64's subnormal range (below 2**-1022, a size near 1e-61) or overflow (near 1e61 on a
#: million faces), and a power of two scales every term exactly.
RESCALE_BEYOND = 100


def analyze(source: MeshSource, where: str, closed: bool = True, rescale: bool = False) -> MeshAnalysis:
    """Integrate and inspect a loaded mesh.

    Parameters
    ----------
    source : MeshSource
    where : str
        The input's name, for error messages.
    closed : bool
        Whether to run the closed test (it costs one sort of the edges). An open mesh's
        moments are summed about the world origin (see below), a closed one's about a local
        origin in the part, which keeps full accuracy wherever the part sits.
    rescale : bool
        Integrate a part whose first block is smaller than ``2**-RESCALE_BEYOND`` or larger
        than ``2**RESCALE_BEYOND`` scaled by the power of two that brings it near 1, so that no
        term under- or overflows; ``scale_exponent`` says by which. Off, such a part's moments
        may underflow (the callers' range checks then refuse them).

    Raises
    ------
    InputError
        No faces, or a NaN or infinite coordinate (with the index of the first such face).
    """
    if source.tetrahedra is not None:
        return _analyze_tetrahedra(source, where)
    if source.face_count == 0:
        raise InputError(where, "the mesh has no faces", "export it again with its faces")
    sums = None
    lo = hi = None
    fast = compiled()
    buckets = None
    if closed and fast is not None and 3 * source.face_count >= 1 << 16:
        # The compiled pass deals the keys to buckets as it makes them: the sort then needs
        # no pass over all of them (p3d_cli.mesh.kernels.Buckets); and only the forward half
        # of them, with the balance of the two directions (ForwardBuckets).
        buckets = ForwardBuckets(3 * source.face_count)
        keys = None
    else:
        keys = key_buffer(3 * source.face_count) if closed else None
    filled = seen = 0
    factor = 1.0
    exponent = 0
    # An indexed mesh goes to the kernels as (vertices, faces) blocks, not gathered first.
    pairs = source.index_blocks() if fast is not None and _indexed(source) else None
    item: Any
    for item in (pairs if pairs is not None else source.read_blocks()):
        block = item
        if pairs is not None:
            vertices, faces = item
            target, size, single = item, len(faces), vertices.dtype == np.float32
        else:
            target, size = block, len(block)
            single = isinstance(block, np.ndarray) and block.dtype == np.float32
        if fast is not None and exponent == 0 and size and (pairs is not None or kernel_takes(block)):
            # The compiled pass: the same bounds, keys and sums, bit for bit, from the file's
            # own records (no float64 copy); None leaves the block to the numpy code below.
            done = _compiled_block(fast, target, size, single, sums, keys, filled, rescale, buckets)
            if done is not None:
                block_lo, block_hi, written, sums = done
                if lo is None:
                    lo, hi = block_lo, block_hi
                else:
                    lo, hi = np.minimum(lo, block_lo), np.maximum(hi, block_hi)
                filled += written
                seen += size
                continue
        if pairs is not None:
            block = vertices[faces]
        # One widening copy per block, in the layout the integrals want; everything else
        # (finite check, bounds, hashes, sums) reads that contiguous copy, never the strided
        # file records.
        cols = columns(block)
        if cols.shape[2] == 0:
            continue                                # an empty block: nothing to add, no bounds
        block_lo, block_hi = _column_bounds(cols)
        # min and max propagate NaN and show any infinity: a finite check for free.
        if not (np.isfinite(block_lo).all() and np.isfinite(block_hi).all()):
            bad = int(np.flatnonzero(~np.isfinite(cols).all(axis=(0, 1)))[0])
            raise InputError(where, f"face {seen + bad} has a NaN or infinite coordinate",
                             "repair or re-export the mesh")
        if sums is None:
            float32 = np.asarray(block).dtype == np.float32
            origin = origin_from_bounds(block_lo, block_hi, float32)
            if rescale:
                exponent = _exponent(float((block_hi - block_lo).max()))
                factor = 2.0 ** exponent
            # (p·2ᵏ - o·2ᵏ) is (p - o)·2ᵏ exactly: the sums are the unscaled ones' bits, scaled.
            sums = MomentSums(origin * factor)
            lo, hi = block_lo, block_hi
        else:
            lo, hi = np.minimum(lo, block_lo), np.maximum(hi, block_hi)
        if keys is not None:
            block_keys = column_edge_keys(cols)     # before the sums shift cols in place
            keys[filled:filled + block_keys.size] = block_keys
            filled += block_keys.size
        elif buckets is not None and not buckets.overflow:
            buckets.add(column_edge_keys(cols))
        if exponent:
            cols *= factor
        sums.add_columns(cols)
        seen += cols.shape[2]
    if seen != source.face_count:
        raise FormatError(where, f"expected {source.face_count} faces but read {seen}",
                          "the file is truncated or corrupt; export it again")
    is_closed = bounding = None
    boundary = 0
    moments = None
    presorted = False
    found = None
    if buckets is not None:
        if not buckets.overflow and buckets.closed():   # each bucket checked where it lies
            del buckets
            is_closed = bounding = True
        else:                                       # the open road wants every key's group
            if not buckets.overflow:
                found = open_groups(source, fast, buckets, pairs is not None)
            del buckets
            if found is None:
                keys, presorted = all_keys(source, fast, pairs is not None)
        filled = 0 if keys is None else keys.size
    if keys is not None:
        keys = keys[:filled]
        if keys_pair_up(keys, presorted):
            is_closed = bounding = True
        else:
            # A 64-bit hash collision can only make a closed mesh look open: most failures
            # prove openness from the sorted keys alone; the few doubtful edges are compared
            # exactly in one more pass.
            found = unbalanced_groups(keys), doubtful_edges(keys), False, None
        del keys
    if found is not None:
        unbalanced, doubtful, pair_up, picked = found
        is_closed = bounding = pair_up
        if not is_closed:
            is_closed = bool(doubtful.size) and sides_pair_up_exactly(source.read_blocks(), doubtful)
            bounding = is_closed or unbalanced.ids.size == 0
            if not bounding:
                if exponent:
                    raise RangeError(where, f"the open mesh is {'too small' if exponent > 0 else 'too large'} to "
                                     "integrate without under- or overflow (its size is "
                                     f"{float((hi - lo).max()):.3g})", "scale it into a unit nearer its size")
                moments = _open_moments(source, sums, unbalanced, lo, hi, picked)
                boundary = unbalanced.edges
    bounds = Bounds(lo.astype(np.float64), hi.astype(np.float64))
    if moments is None:
        moments = sums.moments()
    return MeshAnalysis(moments, bounds, is_closed, seen, bounding=bounding, boundary_edges=boundary,
                        scale_exponent=exponent)


def _indexed(source: MeshSource) -> bool:
    """Whether the kernels read the source's ``(vertices, faces)`` as they are."""
    arrays = source.indexed_arrays()
    if arrays is None:
        return False
    vertices, pieces = arrays
    return (isinstance(vertices, np.ndarray) and vertices.ndim == 2 and vertices.shape[1] == 3
            and vertices.dtype in (np.float32, np.float64) and vertices.dtype.isnative
            and all(isinstance(p, np.ndarray) and p.ndim == 2 and p.shape[1] == 3 and p.dtype.isnative
                    and p.dtype in (np.int32, np.int64) for p in pieces))


def _compiled_block(fast, block, size: int, single: bool, sums: MomentSums | None, keys: np.ndarray | None,
                    filled: int, rescale: bool, buckets: ForwardBuckets | None = None):
    """One block through the compiled kernels: its bounds, its edge keys (into ``keys`` from
    ``filled``, or the forward ones into ``buckets`` with their balance) and its sums; returns
    ``(lo, hi, keys written, sums)``, or None for the numpy code to take the block (a NaN or
    infinity, whose message it words; the first block of a part to be rescaled). A bound of
    ±0, whose sign numpy's min and max decide, is taken from them (``_numpy_box``)."""
    if sums is None:
        box, finite = fast.bounds(block)
        box = np.array(box)
        if not finite:
            return None
        if not box.all():
            box = _numpy_box(block)
        if rescale and _exponent(float((box[3:] - box[:3]).max())):
            return None
        sums = MomentSums(origin_from_bounds(box[:3], box[3:], single))
    balance = backward = 0
    if buckets is not None and not buckets.overflow:
        before = buckets.fill.copy()            # to undo the block's keys if numpy takes it
        printed = buckets.print_fill.copy()
        prints = (buckets.prints, buckets.print_fill) if buckets.whole else ()
        box, finite, totals, magnitude, weighted, written, balance, backward, whole = fast.forward_block(
            block, *sums.origin, buckets.keys, buckets.fill, buckets.cap, buckets.shift, *prints)
        buckets.whole = whole
    else:
        box, finite, totals, magnitude, weighted, written = fast.block(block, *sums.origin, keys, filled)
    box = np.array(box)
    if not finite:
        if buckets is not None and not buckets.overflow:
            buckets.fill[:] = before
            buckets.print_fill[:] = printed
        return None
    if not box.all():
        box = _numpy_box(block)
    if written < 0:                                 # a bucket overflowed
        buckets.overflow = True
        written = 0
    if buckets is not None:
        buckets.balance = (buckets.balance + balance) % (1 << 64)
        buckets.backward += backward
    sums.add_sums(np.array(totals), magnitude, np.array(weighted), size)
    return box[:3], box[3:], written, sums


def _column_bounds(cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ``(lo, hi)`` of a block's columns ``(3, 3, k)``: the reductions that decide the sign
    of a zero bound, for the numpy code and for the kernels' blocks with a bound of ±0."""
    return cols.min(axis=2).min(axis=0), cols.max(axis=2).max(axis=0)


def _numpy_box(block) -> np.ndarray:
    """A block's bounds as the numpy code finds them (``_column_bounds`` of the same copy), as
    the kernels' ``box``: for the blocks with a bound of ±0, whose sums and keys the kernels
    still make."""
    if not isinstance(block, np.ndarray):           # (vertices, faces) of an indexed source
        vertices, faces = block
        block = vertices[faces]
    return np.concatenate(_column_bounds(columns(block)))


def _exponent(extent: float) -> int:
    """The ``k`` that brings ``extent·2**k`` into [0.5, 1) when ``extent`` lies outside
    ``2**±RESCALE_BEYOND`` (else 0; and 0 for a flat or infinite extent).

    At most 1023, the largest ``k`` whose ``2**k`` is finite: a part below 2**-1023 (subnormal
    coordinates) is scaled exactly as far as that goes, and the range checks after scaling back
    refuse what then underflows."""
    if not (0 < extent < np.inf) or 2.0 ** -RESCALE_BEYOND <= extent <= 2.0 ** RESCALE_BEYOND:
        return 0
    return min(-int(np.frexp(extent)[1]), 1023)


def _open_moments(source: MeshSource, sums: MomentSums, unbalanced: Unbalanced,
                  lo: np.ndarray, hi: np.ndarray, picked: list | None = None) -> Moments:
    """An open surface's moments in the world-origin convention.

    An open surface bounds no solid: its divergence-theorem sums depend on the origin of the
    tetrahedra. p3d reports the convention of the reference tools, signed tetrahedra from the
    world origin (docs/method.md, "Open and non-manifold meshes"), computed as the local sums
    plus the net boundary's terms (exact volume, the rest to ~100 bits, with their error bound
    added to the result's), so that a part far from the origin keeps its accuracy whatever the
    number of boundary edges (a soup of loose faces is all boundary).
    """
    terms = boundary_terms(source.read_blocks, unbalanced, sums.origin, lo, hi, picked)
    return sums.moments(terms.sums, terms.error)


def _analyze_tetrahedra(source: MeshSource, where: str) -> MeshAnalysis:
    tets = source.tetrahedra
    if len(tets) == 0:
        raise InputError(where, "the volume mesh has no tetrahedra", "export it again")
    if not np.isfinite(tets).all():
        bad = int(np.flatnonzero(~np.isfinite(tets).reshape(len(tets), -1).all(axis=1))[0])
        raise InputError(where, f"tetrahedron {bad} has a NaN or infinite coordinate", "repair the mesh")
    flat = tets.reshape(-1, 3)
    bounds = Bounds(flat.min(axis=0).astype(np.float64), flat.max(axis=0).astype(np.float64))
    sums = tetrahedron_sums(tets, origin=local_origin(tets))
    return MeshAnalysis(sums.moments(), bounds, None, len(tets), sums.inverted)
