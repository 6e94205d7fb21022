"""The holes of a mesh: its boundary edges joined into simple loops.

A boundary edge is used by one face only. Walking the boundary the other way round from the
faces (each boundary side ``u -> v`` taken as ``v -> u``) goes round the hole with the winding a
patch filling it must have, so the loops come out ready to triangulate: a triangle
``(p_i, p_j, p_k)`` in loop order uses each loop edge against its face.

Where boundaries meet at a vertex (two holes touching at a corner, a hole pinched in the
middle), the vertex has several ways on. The walk takes any, and every closed walk is then
cut at the vertices it passes twice into loops that pass each vertex once: a figure of eight
through one vertex becomes its two holes, whichever way the walk went. A boundary that does
not close (a side whose end no other side leaves) cannot be a hole; its sides are returned
apart.
"""

from __future__ import annotations

import numpy as np


def boundary_loops(starts: np.ndarray, ends: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Simple loops of directed sides ``starts[i] -> ends[i]`` (vertex ids).

    Parameters
    ----------
    starts, ends : (b,) int
        The hole's sides, already turned against their faces.

    Returns
    -------
    loops : list of (k,) int64 arrays
        Side indices (into ``starts``) of each simple loop, in walking order: side ``loop[i]``
        ends where ``loop[i + 1]`` starts.
    stray : (s,) int64
        Sides on no closed loop.
    """
    b = len(starts)
    if b == 0:
        return [], np.zeros(0, dtype=np.int64)
    starts, ends = np.asarray(starts, dtype=np.int64), np.asarray(ends, dtype=np.int64)
    order = np.argsort(starts, kind="stable")
    sorted_starts = starts[order]
    leaving = np.searchsorted(sorted_starts, ends, side="left")
    ways = np.searchsorted(sorted_starts, ends, side="right") - leaving
    if (ways == 1).all():
        following = order[leaving]
        if np.bincount(following, minlength=b).max() == 1:       # a permutation of the sides
            return _single_ways(following, b)
    return _walks(starts, ends, order)


def _single_ways(following: np.ndarray, b: int) -> tuple[list[np.ndarray], np.ndarray]:
    """Every vertex has one side in and one out: the loops are the cycles of ``following``."""
    seen = np.zeros(b, dtype=bool)
    loops = []
    for s in range(b):
        if seen[s]:
            continue
        loop = [s]
        seen[s] = True
        t = int(following[s])
        while t != s:
            loop.append(t)
            seen[t] = True
            t = int(following[t])
        loops.append(np.array(loop, dtype=np.int64))
    return loops, np.zeros(0, dtype=np.int64)


def _walks(starts, ends, order) -> tuple[list[np.ndarray], np.ndarray]:
    """Closed walks over the sides (each used once), cut into simple loops: each walk starts
    at the first side not yet used, in the order given, and leaves a vertex by its first side
    not yet used."""
    unused: dict[int, list[int]] = {}
    for s in order.tolist():
        unused.setdefault(int(starts[s]), []).append(s)
    loops: list[np.ndarray] = []
    stray: list[int] = []
    for s0 in range(len(starts)):
        if s0 not in unused.get(int(starts[s0]), ()):
            continue
        unused[int(starts[s0])].remove(s0)
        walk = [s0]
        while int(ends[walk[-1]]) != int(starts[s0]):
            way = unused.get(int(ends[walk[-1]]))
            if not way:
                break
            walk.append(way.pop(0))
        if int(ends[walk[-1]]) != int(starts[s0]):
            # Not closed: the walk's sides that do close among themselves still can.
            loops_, rest = _cut(walk, starts, ends, closed=False)
            loops += loops_
            stray += rest
            continue
        loops_, rest = _cut(walk, starts, ends, closed=True)
        loops += loops_
        stray += rest
    return loops, np.array(sorted(stray), dtype=np.int64)


def _cut(walk: list[int], starts, ends, closed: bool) -> tuple[list[np.ndarray], list[int]]:
    """Cut a walk at repeated vertices into simple loops (a stack of the vertices passed)."""
    loops: list[np.ndarray] = []
    stack: list[int] = []          # sides on the current path
    at: dict[int, int] = {}        # vertex -> position in the stack where the path left it
    for side in walk:
        u = int(starts[side])
        if u in at:
            # The path came back to u: the sides since it left u form a loop.
            k = at[u]
            loop = stack[k:]
            loops.append(np.array(loop, dtype=np.int64))
            for s in loop:
                at.pop(int(starts[s]), None)
            del stack[k:]
        at[u] = len(stack)
        stack.append(side)
    if closed and stack:
        loops.append(np.array(stack, dtype=np.int64))
        return loops, []
    return loops, stack
