"""Islands (independent groups of bodies) and a spanning forest of each.

Fixed bodies have zero inverse mass, so an impulse on one moves nothing: they do not join
islands. Two free bodies share an island when a chain of constraints between free bodies
links them. Each constraint belongs to the island of its free body (or bodies).

The spanning forest treats all fixed bodies as one "ground" node. Its constraints (tree
constraints) have linearly independent rows: order bodies from the leaves up; each body is
the child of exactly one tree constraint, whose rows restricted to that body (``[E, -[r]ₓ]``,
``[dᵀ, (r × d)ᵀ]``, and ``xᵀ, yᵀ`` on the angular part) have full row rank. So their block of the
system is positive definite, and all possible redundancy lives in the few other constraints
that close loops.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Island:
    """One independent group.

    Attributes
    ----------
    bodies : tuple of int
        Indices of its free bodies, ascending.
    constraints : tuple of int
        Indices of its constraints, ascending (scene order).
    loop : tuple of bool
        Per entry of ``constraints``: True when the constraint closes a loop (is not in the
        spanning forest).
    """

    bodies: tuple[int, ...]
    constraints: tuple[int, ...]
    loop: tuple[bool, ...]


def find_islands(pairs, fixed: np.ndarray) -> tuple[Island, ...]:
    """Islands of the constraint graph.

    Parameters
    ----------
    pairs : sequence of (int, int)
        Body indices ``(a, b)`` of each constraint; never both fixed.
    fixed : (n,) bool

    Returns
    -------
    tuple of Island
        Only islands with at least one constraint; ordered by their smallest body index, so
        the result does not depend on the order of the scene's lists beyond that numbering.
    """
    n = len(fixed)
    ground = n
    adjacency: list[list[tuple[int, int]]] = [[] for _ in range(n + 1)]
    for k, (a, b) in enumerate(pairs):
        u = ground if fixed[a] else a
        v = ground if fixed[b] else b
        adjacency[u].append((v, k))
        adjacency[v].append((u, k))
    component = np.full(n + 1, -1)
    tree = np.zeros(len(pairs), dtype=bool)
    # Ground first, so that every body with a path to a fixed body hangs from ground: then a
    # tree constraint's child is always a free body.
    label = 0
    roots = [ground] + list(range(n))
    for root in roots:
        if root != ground and (fixed[root] or component[root] >= 0):
            continue
        queue = deque([root])
        if root != ground:
            component[root] = label
            label += 1
        while queue:
            u = queue.popleft()
            for v, k in adjacency[u]:
                if v == ground or component[v] >= 0:
                    continue
                if u == ground:
                    component[v] = label
                    label += 1
                else:
                    component[v] = component[u]
                tree[k] = True
                queue.append(v)
    return _group(pairs, fixed, component, tree)


def _group(pairs, fixed, component, tree) -> tuple[Island, ...]:
    # BFS from ground labelled each ground child separately: merge labels joined by constraints.
    n = len(fixed)
    parent = list(range(int(component.max()) + 1 if n else 0))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in pairs:
        if not fixed[a] and not fixed[b]:
            ra, rb = find(component[a]), find(component[b])
            if ra != rb:
                parent[max(ra, rb)] = min(ra, rb)
    members: dict[int, list[int]] = {}
    for i in range(n):
        if not fixed[i] and component[i] >= 0:
            members.setdefault(find(component[i]), []).append(i)
    owner = {}
    for root, bodies in members.items():
        for i in bodies:
            owner[i] = root
    cons: dict[int, list[int]] = {}
    for k, (a, b) in enumerate(pairs):
        free = a if not fixed[a] else b
        cons.setdefault(owner[free], []).append(k)
    islands = []
    for root in sorted(cons, key=lambda r: min(members[r])):
        ks = cons[root]
        islands.append(Island(tuple(sorted(members[root])), tuple(ks), tuple(not tree[k] for k in ks)))
    return tuple(islands)
