"""The broad phase's compiled road (``p3d_cli.mesh._kernels``): the pairs of faces whose boxes
overlap, found by the compiled kernels on ``p3d_cli.mesh.broadphase``'s levels and cells, with
the certified fans' pairs set aside on the way (docs/method.md, "Broad phase"). The caller
takes ``broadphase``'s numpy road when ``compiled_pairs`` returns None.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.mesh.broadphase import _MAX_CELL, Pairs, _levels_of, box_frame
from p3d_cli.mesh.kernels import key_buffer

#: Pairs per call of the compiled grid (two int64 arrays of this length: 1 MB).
COMPILED_PAIRS = 1 << 16
#: Bytes per entry of the compiled grid (its box and vertex ids).
ENTRY = 36
#: Faces per window of the compiled grid's scan (their entries made together).
WINDOW = 1 << 16
#: The compiled grid's x cells: the level's cell size over 2**FINE_X (where the keys' bits allow).
FINE_X = 8
#: Bins along each axis of a coarser level's boxes' shadow (``Shadow``), for its probes.
SHADOW_BINS = 1 << 12


def compiled_pairs(fast, points: np.ndarray, faces: np.ndarray, live: np.ndarray,
                   certified: np.ndarray | None) -> Pairs | None:
    """The pairs of ``pair_blocks`` by the compiled kernels (``fast``), as face numbers: chunks
    ``(i, j)``, ``i < j``, of the faces ``live`` whose boxes (``intersections._boxes``'s, made
    here) overlap, exactly rather than within a quantisation step, and, when ``certified``
    (per point) is given, that share no certified vertex (``triangle_pairs.uncertified``).
    None when the compiled grid cannot hold the mesh (a level's cells and the box numbers do
    not fit one 64-bit key: parts very far apart for their faces' size; more than 2**31
    points): the caller then takes the numpy road.

    The levels and cells are ``pair_blocks``'s, but each face is entered once, in the cell of
    its box's lower corner, and looks for its partners: box ``b`` meets box ``a`` only if, along
    each axis, ``b``'s lower-corner cell lies between ``a``'s lower-corner cell minus the most
    cells a box of ``b``'s level spans and ``a``'s upper-corner cell (cells are monotone in the
    coordinates: no rounding argument needed). A level's own pairs are found by each face among
    the entries after it in key order; a finer face looks up each coarser level."""
    n = len(live)
    if n < 2 or len(points) >= 2**31:
        return None
    points = np.ascontiguousarray(points, dtype=np.float64)
    faces = np.ascontiguousarray(faces)
    if faces.dtype not in (np.int32, np.int64):
        faces = faces.astype(np.int64)
    live = np.ascontiguousarray(live)
    if live.dtype not in (np.int32, np.int64):
        live = live.astype(np.int64)
    centre, shift = box_frame(points)
    frame = ((float(centre[0]), float(centre[1]), float(centre[2])), shift)
    extent = np.empty(n, dtype=np.float32)
    least, most = fast.face_extents(points, faces, live, frame, extent)
    cell, level = _levels_of(extent)
    del extent
    origin, top = np.array(least), np.array(most)
    fbits = max(int(n - 1).bit_length(), 1)
    index = np.int32 if n < 2**31 else np.int64
    grids = []
    for L in np.unique(level).tolist():
        # Cells of the level's size across y and z (rows), finer along x, down to 1/2**FINE_X
        # of it as the key's bits allow: a row is scanned only over the x range that can hold
        # a partner's lower corner.
        base = cell * 2.0 ** L
        for fine in range(FINE_X, -1, -1):
            cell_sizes = np.array([base / 2.0 ** fine, base, base])
            cells = np.clip(np.floor((top - origin) / cell_sizes), 0, _MAX_CELL).astype(np.int64)
            bits = tuple(max(int(c).bit_length(), 1) for c in cells)
            if sum(bits) + fbits <= 64 and fbits <= 62:
                break
        else:
            return None
        grids.append((L, tuple(float(x) for x in cell_sizes), bits))
    marks = None if certified is None else np.ascontiguousarray(certified, dtype=bool).view(np.uint8)
    corner = tuple(float(x) for x in origin)
    built = []
    for L, sizes, bits in grids:
        # The keys in the members' order (members None: every live face, in order), sorted.
        members = np.flatnonzero(level == L).astype(index) if len(grids) > 1 else None
        keys = np.empty(n if members is None else members.size, dtype=np.uint64)
        span = fast.grid_keys(points, faces, live, frame, members, (corner, sizes, bits, fbits, (0, 0, 0)), keys)
        fast.sort(keys)
        built.append((keys, members, (corner, sizes, bits, fbits, span)))
    del level

    # The finer levels' windows' entries, made once (by the level's own scan) for every
    # coarser level that looks them up (a mesh of many levels, such as one with long slivers,
    # would otherwise make its finest level's entries again for each coarser level).
    made: dict[tuple[int, int], np.ndarray] = {}

    def fill(keys, members):
        """The entries of ``keys`` (boxes and vertex ids beside the keys: scans read in order)."""
        entries = _unpaged((keys.size, ENTRY))
        fast.grid_fill(points, faces, live, frame, keys, fbits, members, marks, entries)
        return entries

    def run(keys, entries, window, members, grid, queries, start, stop) -> Pairs:
        query_keys, query_entries, query_members, positions = queries or (None, None, None, None)
        out_i, out_j = _unpaged(COMPILED_PAIRS, np.int64), _unpaged(COMPILED_PAIRS, np.int64)
        at = start
        while at < stop:
            at, written = fast.grid_pairs(keys, entries, window, members, live, grid, query_keys, query_entries,
                                          query_members, positions, at, stop, out_i, out_j)
            if written < 0:                     # one face's pairs did not fit: more room
                out_i, out_j = _unpaged(2 * out_i.size, np.int64), _unpaged(2 * out_j.size, np.int64)
                continue
            if written:
                yield out_i[:written].copy(), out_j[:written].copy()

    def own(at, keys, members, grid) -> Pairs:
        """A level's own pairs, WINDOW faces at a time, with the entries of the rows they scan
        (up to the last one's row plus the span: a few rows, not the whole level's). Below
        the coarsest level, each window's own entries are kept for the coarser levels' probes."""
        _, _, (bx, by, _), _, (_, sy, sz) = grid
        row_shift = bx + fbits
        entries = _unpaged((0, ENTRY))
        have, done = 0, 0                        # entries[:done - have] are those of keys[have:done]
        for q0 in range(0, keys.size, WINDOW):
            q1 = min(keys.size, q0 + WINDOW)
            row = int(keys[q1 - 1]) >> row_shift
            z, y = row >> by, row & ((1 << by) - 1)
            top = ((z + sz) << by) | min(y + sy, (1 << by) - 1)
            bound = (top + 1) << row_shift
            end = keys.size if bound >= 2**64 else int(np.searchsorted(keys, np.uint64(bound), side="left"))
            # The entries the last window made past q0 are kept (moved down), the rest made.
            kept = max(done - q0, 0)
            old = entries[q0 - have:done - have].copy() if kept else None
            if end - q0 > len(entries):
                entries = _unpaged((max(end - q0, 2 * len(entries)), ENTRY))
            if old is not None:
                entries[:kept] = old
            del old
            if end > q0 + kept:
                fast.grid_fill(points, faces, live, frame, keys[q0 + kept:end], fbits, members, marks,
                               entries[kept:end - q0])
            have, done = q0, end
            if at < len(built) - 1:
                made[(at, q0)] = entries[:q1 - q0].copy()
            yield from run(keys, entries[:end - q0], q0, members, grid, None, q0, q1)

    def probes(at) -> Pairs:
        """The finer levels' faces near a coarser level's faces, looking its cells up."""
        keys, members, grid = built[at]
        entries = fill(keys, members)
        box = entries.view(np.float32)
        box_lo, box_hi = box[:, :3].min(axis=0), box[:, 3:6].max(axis=0)
        shadows = [Shadow(box[:, k], box[:, 3 + k], float(box_lo[k]), float(box_hi[k])) for k in range(3)]
        last = at == len(built) - 1
        for finer, (finer_keys, finer_members, _) in enumerate(built[:at]):
            for q0 in range(0, finer_keys.size, WINDOW):
                query_keys = finer_keys[q0:q0 + WINDOW]
                query_entries = made.pop((finer, q0), None) if last else made.get((finer, q0))
                if query_entries is None:
                    query_entries = fill(query_keys, finer_members)
                    if not last:
                        made[(finer, q0)] = query_entries
                corners = query_entries.view(np.float32)
                near = np.ones(query_keys.size, dtype=bool)
                for k in range(3):
                    near &= (corners[:, k] <= box_hi[k]) & (corners[:, 3 + k] >= box_lo[k])
                for k in range(3):
                    rows = np.flatnonzero(near)
                    near[rows] = shadows[k].meets(corners[rows, k], corners[rows, 3 + k])
                positions = np.flatnonzero(near).astype(index)
                if positions.size:
                    yield from run(keys, entries, 0, members, grid,
                                   (query_keys, query_entries, finer_members, positions), 0, positions.size)

    def pairs() -> Pairs:
        for at, (keys, members, grid) in enumerate(built):
            yield from own(at, keys, members, grid)
            if at:
                yield from probes(at)

    return pairs()


class Shadow:
    """The union of extents ``[lo, hi]`` along one axis (within ``least`` to ``most``), on
    ``SHADOW_BINS`` bins: an extent that covers no bin of it meets none of them. A coarser
    level's probes skip the finer boxes far from every one of its boxes (the flat discs of
    slivers of filled holes, whose one box around them all holds most of the mesh).

    Exact: the bins are a monotone map of the coordinates (rounded differences and products,
    ``floor`` and clipping keep the order), so two extents that share a point share its bin.
    """

    def __init__(self, lo: np.ndarray, hi: np.ndarray, least: float, most: float):
        self.least = least
        span = most - least
        # One bin (every extent meets it) for a point, or a span too large or too small for
        # its bins' arithmetic.
        self.scale = SHADOW_BINS / span if most > least and np.isfinite(span) else 0.0
        if not np.isfinite(self.scale):
            self.scale = 0.0
        first, last = self._bins(lo), self._bins(hi)
        change = np.zeros(SHADOW_BINS + 1, dtype=np.int64)
        np.add.at(change, first, 1)
        np.add.at(change, last + 1, -1)
        covered = np.cumsum(change[:SHADOW_BINS]) > 0
        self.before = np.concatenate([[0], np.cumsum(covered)])     # covered bins before each

    def _bins(self, x: np.ndarray) -> np.ndarray:
        if self.scale == 0:
            return np.zeros(len(x), dtype=np.int64)
        with np.errstate(over="ignore"):      # far beyond the span: infinite, clipped below
            at = np.floor((x.astype(np.float64) - self.least) * self.scale)
        return np.clip(at, 0, SHADOW_BINS - 1).astype(np.int64)

    def meets(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Whether each extent ``[lo, hi]`` covers a bin the level's boxes cover."""
        return self.before[self._bins(hi) + 1] > self.before[self._bins(lo)]


def _unpaged(shape, dtype=np.uint8) -> np.ndarray:
    """An uninitialised array in ordinary pages (``kernels.key_buffer``: no huge-page request,
    whose compaction cost more system time than the work)."""
    size = int(np.prod(shape))
    return key_buffer((size * np.dtype(dtype).itemsize + 7) // 8).view(np.uint8)[:size * np.dtype(dtype).itemsize] \
        .view(dtype).reshape(shape)
