"""Every constraint's rows at once: the arrays of one scene, prepared once, evaluated per step.

A constraint type's module defines it one constraint at a time (``jacobian``, ``position_error``),
which is the clearest statement of its equations and what reporting uses. Stepping evaluates the
same equations thousands of times, where a Python loop over constraints costs far more than the
arithmetic; so each type's module also gives its array form, ``Rows``: the per-scene constants
of that type's constraints as arrays, and their errors and rows for all of them in a fixed
handful of numpy calls. ``RowSet`` holds what every type shares (body indices, attachment
offsets from the centres of mass, where each constraint's rows go) and asks each type present in
the scene, in the registry's order, for its part.

Rows are in scene order: constraint 0's rows, then constraint 1's, and within a constraint in
the order of its module.

The body-frame vectors a type declares in its module's ``TURNED`` (value name and side, such
as a hinge's axes) are turned into the world frame by ``geometry`` with the attachment offsets,
in one product; the type reads them back as ``geo.turned[g]``, in order.

A type's ``Rows(specs, ks, offsets)`` (``ks`` the scene indices of its constraints) has:

- ``template(ja, jb)``: writes its rows' constant entries (the ``±E`` of a ball's rows);
- ``errors(geo, g, out)`` and ``jacobian(geo, g, ja, jb)``: write its rows' position errors and
  variable entries (``g`` is its place in ``geo.turned`` and ``geo.memo``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.constraints.registry import CONSTRAINT_TYPES


class Geometry:
    """World geometry of every constraint at one instant (arrays over constraints).

    Attributes
    ----------
    r_a, r_b : (c, 3) float64
        Attachment points minus centres of mass, world frame.
    gap : (c, 3) float64
        ``p_b - p_a``, the attachment points' separation.
    turned : list of tuple
        Per type present (``RowSet.groups``' order), its ``TURNED`` vectors in the world frame.
    memo : list of dict
        Per type present, what its ``errors`` and ``jacobian`` share at this instant (a hinge's
        frames), computed once.
    """

    __slots__ = ("r_a", "r_b", "gap", "turned", "memo")

    def __init__(self, r_a, r_b, gap, turned) -> None:
        self.r_a, self.r_b, self.gap, self.turned = r_a, r_b, gap, turned
        self.memo: list[dict] = [{} for _ in turned]


class RowSet:
    """The constraint rows of one scene.

    Parameters
    ----------
    scene : Scene
    index : dict
        Body name -> index in the world arrays.
    com_body : (n, 3) float64
        Centres of mass in the body frames.

    Attributes
    ----------
    a, b : (c,) int
        Body indices of each constraint.
    row_a, row_b : (m,) int
        Body indices of each row's two sides.
    row_constraint : (m,) int
        Constraint of each row.
    offsets : (c + 1,) int
        First row of each constraint.
    groups : list
        The ``Rows`` of each constraint type present, in the registry's order.
    """

    def __init__(self, scene, index: dict, com_body: np.ndarray) -> None:
        specs = scene.constraints
        self.where = [c.where for c in specs]
        self.a = np.array([index[c.a] for c in specs], dtype=np.intp)
        self.b = np.array([index[c.b] for c in specs], dtype=np.intp)
        sizes = np.array([CONSTRAINT_TYPES[c.type].EQUATIONS for c in specs], dtype=np.intp)
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
        self.m = int(self.offsets[-1])
        self.row_constraint = np.repeat(np.arange(len(specs)), sizes)
        self.row_a, self.row_b = self.a[self.row_constraint], self.b[self.row_constraint]
        # Attachment offsets from the centres of mass, body frames: constant for the scene.
        self.off_a = np.array([c.attach_a for c in specs]).reshape(-1, 3) - com_body[self.a]
        self.off_b = np.array([c.attach_b for c in specs]).reshape(-1, 3) - com_body[self.b]
        self.groups = []
        # Every body-frame vector (attachment offsets, then each type's own) turned in one product.
        rot_index, vectors = [self.a, self.b], [self.off_a, self.off_b]
        self._turned: list[list[tuple[int, int]]] = []
        start = 2 * len(specs)
        for name, module in CONSTRAINT_TYPES.items():
            ks = np.array([k for k, c in enumerate(specs) if c.type == name], dtype=np.intp)
            if not len(ks):
                continue
            self.groups.append(module.Rows(specs, ks, self.offsets))
            spans = []
            for name, side in module.TURNED:
                rot_index.append((self.a if side == "a" else self.b)[ks])
                vectors.append(np.array([specs[k].values[name] for k in ks], dtype=np.float64).reshape(-1, 3))
                spans.append((start, start + len(ks)))
                start += len(ks)
            self._turned.append(spans)
        self.rot_index = np.concatenate(rot_index)
        self.com_index = np.concatenate([self.a, self.b])
        self.body_vectors = np.concatenate(vectors)[:, :, None]
        self.template_a, self.template_b = np.zeros((self.m, 6)), np.zeros((self.m, 6))
        for rows in self.groups:
            rows.template(self.template_a, self.template_b)

    def geometry(self, com: np.ndarray, rot: np.ndarray) -> Geometry:
        """World geometry at centres of mass ``com`` (n, 3) and rotations ``rot`` (n, 3, 3)."""
        c = len(self.a)
        v = (rot[self.rot_index] @ self.body_vectors)[:, :, 0]
        p = com[self.com_index] + v[:2 * c]
        turned = [tuple(v[s:e] for s, e in spans) for spans in self._turned]
        return Geometry(v[:c], v[c:2 * c], p[c:] - p[:c], turned)

    def errors(self, geo: Geometry) -> np.ndarray:
        """(m,) position equations ``C``, scene row order (the modules' ``position_error``)."""
        out = np.empty(self.m)
        for g, rows in enumerate(self.groups):
            rows.errors(geo, g, out)
        return out

    def jacobian(self, geo: Geometry) -> tuple[np.ndarray, np.ndarray]:
        """``(JA, JB)``, each (m, 6): row ``i`` is ``JA[i] · u[row_a[i]] + JB[i] · u[row_b[i]]``."""
        ja, jb = self.template_a.copy(), self.template_b.copy()
        for g, rows in enumerate(self.groups):
            rows.jacobian(geo, g, ja, jb)
        return ja, jb

    def apply(self, ja: np.ndarray, jb: np.ndarray, u: np.ndarray) -> np.ndarray:
        """(m,) ``J u`` for body motions ``u`` (n, 6)."""
        return (ja * u[self.row_a] + jb * u[self.row_b]).sum(axis=1)
