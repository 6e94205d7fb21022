"""Solving ``(J W Jᵀ) λ = b`` for constraint impulses, island by island.

With ``J`` the stacked constraint rows (each constraint's ``ME`` blocks) and ``W = M⁻¹`` the
block-diagonal inverse mass (``m⁻¹ E`` and the world inverse inertia ``R I⁻¹ Rᵀ``; zero for fixed
bodies), the system is ``(J W Jᵀ) λ = b``: for a velocity solve ``b = -J u``, for a position
correction ``b = -C``. ``J W Jᵀ`` is symmetric positive semi-definite; it is singular exactly
when constraints are redundant (a closed loop, a constraint given twice). Then ``λ`` is the
minimum-norm (least-squares) solution and the rank is reported; the resulting motion
``W Jᵀ λ`` is the same for every solution, because it is the mass-weighted projection onto the
motions the constraints allow.

``SystemPlan`` is built once per scene: which island takes which path, and the index maps that
put each row's ``(J_a, J_b)`` into the island's matrices. ``SystemPlan.factorise`` then builds and
factorises every island's system for one set of rows; the ``Factorisation`` it returns solves
any number of right-hand sides (the position correction of a step reuses the one of the
velocity solve that ended the previous step: same rows, same matrix). Three paths:

- **dense** (at most ``DENSE_LIMIT`` rows): an eigendecomposition (pseudo-inverse with a
  relative tolerance) and one step of iterative refinement. Islands of the same size are
  stacked and decomposed in one batched call, so many small islands cost one call, not many.
- **body space** (more rows than the island's ``6 nb`` degrees of freedom, which are at most
  ``BODY_SPACE_LIMIT``): with ``W = L Lᵀ`` and ``G = J L`` (``m × 6nb``), ``J W Jᵀ = G Gᵀ``, and
  the thin SVD ``G = U S Vᵀ`` gives the minimum-norm ``λ = U S⁻² Uᵀ b`` and the rank (the
  eigenvalues of ``G Gᵀ`` are ``S²``). Time and memory grow linearly with the rows, so 2,000
  duplicates of a joint cost 2,000 times one joint, not 2,000².
- **sparse**: a sparse LU factorisation of the spanning-forest block, which is positive
  definite (see ``islands``), and a dense Schur complement for the few loop-closing rows, whose
  eigendecomposition gives the rank; the minimum-norm ``λ`` is the particular solution minus its
  projection on the null space ``[-A_TT⁻¹ A_TL Z; Z]``. A chain is banded, so its factorisation
  costs time linear in its length.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

#: Islands with at most this many equations are solved densely.
DENSE_LIMIT = 240
#: Islands with more rows than degrees of freedom, and at most this many degrees of freedom,
#: are solved in body space.
BODY_SPACE_LIMIT = 240
#: An eigenvalue below this fraction of the largest diagonal entry of ``J W Jᵀ`` counts as
#: zero (a redundant direction). The system's entries are ``1/mass`` and ``r²/inertia`` sized,
#: so the diagonal is its natural scale; 1e-9 sits far above rounding (~1e-16 relative) and
#: far below any physically meaningful stiffness ratio.
RANK_RTOL = 1e-9


@dataclass(frozen=True)
class ImpulseSolution:
    """Multipliers of every row and what the solve learned about the system.

    Attributes
    ----------
    lam : (m,) float64
        Multipliers, scene row order.
    offsets : (c + 1,) int
        First row of each constraint.
    rank : int
        Rank of ``J W Jᵀ`` summed over islands.
    equations : int
    island_ranks : tuple of (int, int)
        ``(rank, equations)`` per island.
    """

    lam: np.ndarray
    offsets: np.ndarray
    rank: int
    equations: int
    island_ranks: tuple[tuple[int, int], ...]

    @cached_property
    def multipliers(self) -> tuple[np.ndarray, ...]:
        """One array per constraint, scene order (built once: reporting reads it per constraint)."""
        o = self.offsets
        return tuple(self.lam[o[k]:o[k + 1]] for k in range(len(o) - 1))


class _Island:
    """Index maps of one island (or a stack of equally sized dense islands)."""

    def __init__(self, islands, rows, active) -> None:
        # rows (m,) scene rows of each island, bodies its free bodies; stacked over islands.
        self.count = len(islands)
        self.rows = np.array([np.concatenate([np.arange(rows.offsets[k], rows.offsets[k + 1])
                                              for k in isl.constraints]) for isl in islands], dtype=np.intp)
        self.bodies = np.array([isl.bodies for isl in islands], dtype=np.intp)
        self.m, self.nb = self.rows.shape[1], self.bodies.shape[1]
        self.loop = [np.concatenate([np.full(rows.offsets[k + 1] - rows.offsets[k], loop)
                                     for k, loop in zip(isl.constraints, isl.loop)]) for isl in islands]
        # Islands share no free body, so one array over all bodies holds each body's column in
        # its own island (-1: fixed, or in no island here).
        local = np.full(len(active), -1, dtype=np.intp)
        local[self.bodies] = np.arange(self.nb)[None, :]
        self.sides = []
        for body_of_row in (rows.row_a, rows.row_b):
            where = local[body_of_row[self.rows]]                                   # (k, m)
            slot, lrow = np.nonzero(where >= 0)
            self.sides.append((slot, lrow, where[slot, lrow], self.rows[slot, lrow]))

    def jacobian(self, ja, jb) -> np.ndarray:
        """(k, m, nb, 6) dense rows of the stacked islands (fixed bodies' columns dropped)."""
        jac = np.zeros((self.count, self.m, self.nb, 6))
        for (slot, lrow, lbody, row), block in zip(self.sides, (ja, jb)):
            jac[slot, lrow, lbody] = block[row]
        return jac


class SystemPlan:
    """How each island of a scene is solved, prepared once.

    Parameters
    ----------
    islands : sequence of Island
    rows : RowSet
    active : (n,) bool
        Free bodies with mass properties.

    An island of at most ``DENSE_LIMIT`` equations is solved dense (the module's value, read
    when the plan is made).
    """

    def __init__(self, islands, rows, active) -> None:
        self.m = rows.m
        self.offsets = rows.offsets
        self.islands = islands
        self.order: list[tuple] = []  # per island (path, group, slot), for the rank report
        self.dense: dict[tuple[int, int], list] = {}
        self.single: list[tuple[str, object]] = []
        for isl in islands:
            m = sum(int(rows.offsets[k + 1] - rows.offsets[k]) for k in isl.constraints)
            dof = 6 * len(isl.bodies)
            if m <= DENSE_LIMIT:
                group = self.dense.setdefault((m, len(isl.bodies)), [])
                self.order.append(("dense", (m, len(isl.bodies)), len(group)))
                group.append(isl)
            else:
                path = "body" if dof < m and dof <= BODY_SPACE_LIMIT else "sparse"
                self.order.append((path, len(self.single), 0))
                self.single.append((path, isl))
        self.dense_maps = {key: _Island(group, rows, active) for key, group in self.dense.items()}
        self.single_maps = [(path, _Island([isl], rows, active)) for path, isl in self.single]
        self.dense_slot = {key: i for i, key in enumerate(self.dense_maps)}
        self.scatter = _scatter_matrix(len(active), rows.row_a, rows.row_b)
        self.n = len(active)

    def factorise(self, ja, jb, inv_mass, inv_inertia) -> "Factorisation":
        """Build and factorise every island's ``J W Jᵀ`` for rows ``(ja, jb)`` (m, 6), with the
        world inverse masses ``inv_mass`` (n,) and inertias ``inv_inertia`` (n, 3, 3)."""
        parts: list = [_DenseStack(maps, ja, jb, inv_mass, inv_inertia) for maps in self.dense_maps.values()]
        keys = list(self.dense_maps)
        for path, maps in self.single_maps:
            cls = _BodySpace if path == "body" else _Sparse
            parts.append(cls(maps, ja, jb, inv_mass, inv_inertia))
        ranks = []
        for path, group, slot in self.order:
            part = parts[self.dense_slot[group]] if path == "dense" else parts[len(keys) + group]
            ranks.append((int(part.ranks[slot]), part.maps.m))
        return Factorisation(parts, self, tuple(ranks), (ja, jb, inv_mass, inv_inertia))


class Factorisation:
    """The factorised system of every island: ``solve`` for ``λ``, or ``motion`` for ``W Jᵀ λ``."""

    def __init__(self, parts, plan, island_ranks, arrays) -> None:
        self.parts, self.plan, self.island_ranks = parts, plan, island_ranks
        self.arrays = arrays
        self.rank = sum(r for r, _ in island_ranks)
        self.equations = sum(e for _, e in island_ranks)

    def solve(self, b: np.ndarray) -> ImpulseSolution:
        """Minimum-norm least-squares ``λ`` of ``(J W Jᵀ) λ = b`` (rows of islands only)."""
        lam = np.zeros(self.plan.m)
        for part in self.parts:
            rows = part.maps.rows
            lam[rows] = part.solve(b[rows])
        return ImpulseSolution(lam, self.plan.offsets, self.rank, self.equations, self.island_ranks)

    def motion(self, b: np.ndarray) -> np.ndarray:
        """``W Jᵀ λ`` for that ``λ``: (n, 6) linear and angular change of every body.

        Dense islands apply their ``W Jᵀ`` blocks to their ``λ`` directly; the others sum the
        rows of ``λ`` onto the bodies.
        """
        out = np.zeros((self.plan.n, 6))
        lam = None
        for part in self.parts:
            rows = part.maps.rows
            if isinstance(part, _DenseStack):
                out[part.maps.bodies.ravel()] = part.motion(b[rows]).reshape(-1, 6)
            else:
                lam = np.zeros(self.plan.m) if lam is None else lam
                lam[rows] = part.solve(b[rows])
        if lam is not None:
            ja, jb, inv_mass, inv_inertia = self.arrays
            force = self.plan.scatter @ np.concatenate([ja * lam[:, None], jb * lam[:, None]])
            out[:, :3] += inv_mass[:, None] * force[:, :3]
            out[:, 3:] += np.einsum("nij,nj->ni", inv_inertia, force[:, 3:])
        return out


class PendingSolution:
    """The rank of a solve now, its multipliers when asked for (stepping reports only the last)."""

    def __init__(self, factor: Factorisation, b: np.ndarray) -> None:
        self.factor, self.b = factor, b
        self._solution: ImpulseSolution | None = None
        self.rank, self.equations, self.island_ranks = factor.rank, factor.equations, factor.island_ranks

    @property
    def solution(self) -> ImpulseSolution:
        if self._solution is None:
            self._solution = self.factor.solve(self.b)
        return self._solution

    @property
    def multipliers(self) -> tuple[np.ndarray, ...]:
        return self.solution.multipliers


#: Above this many entries the row-to-body summation matrix is sparse.
_DENSE_SCATTER = 20000


def _scipy_sparse():
    """``scipy.sparse``, which only large islands need: scipy is the optional extra ``solve``.

    Raises
    ------
    MissingExtraError
    """
    try:
        import scipy.sparse as sp
        import scipy.sparse.linalg  # noqa: F401 - splu, loaded with it
    except ImportError:
        from p3d_cli.errors import MissingExtraError, install_hint

        raise MissingExtraError("solve", "a constraint island this large needs scipy (sparse factorisation), "
                                "which is not installed", install_hint("solve", "'scipy>=1.10'")) from None
    return sp


def _scatter_matrix(n: int, row_a: np.ndarray, row_b: np.ndarray):
    """``S`` (n, 2m) with ``S @ [X_a; X_b]`` the per-body sums of rows ``X_a`` on their side-a
    bodies plus rows ``X_b`` on their side-b bodies (one matrix product per ``W Jᵀ λ``)."""
    bodies = np.concatenate([row_a, row_b])
    if n * bodies.size <= _DENSE_SCATTER:
        out = np.zeros((n, bodies.size))
        out[bodies, np.arange(bodies.size)] = 1.0
        return out
    sp = _scipy_sparse()
    return sp.csr_matrix((np.ones(bodies.size), (bodies, np.arange(bodies.size))), shape=(n, bodies.size))


def _weighted(jac, inv_mass_b, inv_inertia_b):
    """``J W`` for stacked dense rows ``jac`` (k, m, nb, 6)."""
    out = np.empty_like(jac)
    np.multiply(jac[..., :3], inv_mass_b[:, None, :, None], out=out[..., :3])
    # Row times the (symmetric) inverse inertia of its body: (k, m, nb, 1, 3) @ (k, 1, nb, 3, 3).
    out[..., 3:] = (jac[..., None, 3:] @ inv_inertia_b[:, None])[..., 0, :]
    return out


class _DenseStack:
    def __init__(self, maps, ja, jb, inv_mass, inv_inertia) -> None:
        self.maps = maps
        k, m = maps.count, maps.m
        jac = maps.jacobian(ja, jb)
        weighted = _weighted(jac, inv_mass[maps.bodies], inv_inertia[maps.bodies])
        system = jac.reshape(k, m, -1) @ weighted.reshape(k, m, -1).transpose(0, 2, 1)
        system = 0.5 * (system + system.transpose(0, 2, 1))
        values, self.vectors = np.linalg.eigh(system)
        diag = system.reshape(k, -1)[:, ::m + 1].max(axis=1)
        keep = values > RANK_RTOL * np.maximum(diag, 0.0)[:, None]
        self.inv = np.divide(1.0, values, out=np.zeros_like(values), where=keep)
        self.system, self.ranks = system, keep.sum(axis=1)
        self.weighted_t = weighted.reshape(k, m, -1).transpose(0, 2, 1)

    def motion(self, b):
        """(k, 6 nb) ``W Jᵀ λ`` of each stacked island for right-hand sides ``b`` (k, m).

        ``λ`` comes from the refined solve, not from a precomputed ``W Jᵀ A⁺`` operator: an
        explicit operator carries the eigendecomposition's rounding times the condition
        number into the motion (1e-7 m/s on an ill-conditioned island, against 1e-13).
        """
        return (self.weighted_t @ self.solve(b)[..., None])[..., 0]

    def _apply(self, b):
        v = self.vectors
        return (v @ (self.inv * (b[:, None, :] @ v)[:, 0])[..., None])[..., 0]

    def solve(self, b):
        lam = self._apply(b)
        # One step of iterative refinement: the eigendecomposition's rounding grows with the
        # condition number; re-solving for the residual recovers the lost digits.
        return lam + self._apply(b - (self.system @ lam[..., None])[..., 0])


class _BodySpace:
    def __init__(self, maps, ja, jb, inv_mass, inv_inertia) -> None:
        self.maps = maps
        jac = maps.jacobian(ja, jb)[0]                        # (m, nb, 6)
        bodies = maps.bodies[0]
        # W = L Lᵀ per body: sqrt(1/m) E and the Cholesky factor of the world inverse inertia.
        chol = np.linalg.cholesky(inv_inertia[bodies])
        g = np.empty_like(jac)
        g[..., :3] = jac[..., :3] * np.sqrt(inv_mass[bodies])[None, :, None]
        g[..., 3:] = np.einsum("mbj,bjl->mbl", jac[..., 3:], chol)
        self.g = g.reshape(maps.m, -1)
        u, s, _ = np.linalg.svd(self.g, full_matrices=False)
        diag = float(np.max(np.einsum("mi,mi->m", self.g, self.g)))
        keep = s * s > RANK_RTOL * diag
        self.u, self.inv = u[:, keep], 1.0 / (s[keep] * s[keep])
        self.ranks = np.array([int(keep.sum())])

    def solve(self, b):
        b = b[0]
        lam = self.u @ (self.inv * (self.u.T @ b))
        lam = lam + self.u @ (self.inv * (self.u.T @ (b - self.g @ (self.g.T @ lam))))
        return lam[None, :]


class _Sparse:
    def __init__(self, maps, ja, jb, inv_mass, inv_inertia) -> None:
        sp = _scipy_sparse()
        splu = sp.linalg.splu

        self.maps = maps
        m, nb = maps.m, maps.nb
        data, rws, cols = [], [], []
        for (_, lrow, lbody, row), block in zip(maps.sides, (ja, jb)):
            data.append(block[row].ravel())
            rws.append(np.repeat(lrow, 6))
            cols.append((6 * lbody[:, None] + np.arange(6)).ravel())
        jac = sp.csr_matrix((np.concatenate(data), (np.concatenate(rws), np.concatenate(cols))), shape=(m, 6 * nb))
        bodies = maps.bodies[0]
        w_blocks = np.zeros((nb, 6, 6))
        w_blocks[:, [0, 1, 2], [0, 1, 2]] = inv_mass[bodies][:, None]
        w_blocks[:, 3:, 3:] = inv_inertia[bodies]
        weights = sp.bsr_matrix((w_blocks, np.arange(nb), np.arange(nb + 1)), shape=(6 * nb, 6 * nb)).tocsr()
        system = (jac @ weights @ jac.T).tocsc()
        loop = maps.loop[0]
        self.tree, self.loop = np.flatnonzero(~loop), np.flatnonzero(loop)
        a_tt = system[self.tree][:, self.tree].tocsc()
        # The spanning-forest block is symmetric positive definite: a symmetric ordering with no
        # pivoting keeps a banded (chain) or tree structure sparse.
        self.lu = splu(a_tt, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        self.ranks = np.array([m])
        if self.loop.size == 0:
            return
        self.a_tl = system[self.tree][:, self.loop].toarray()
        a_ll = system[self.loop][:, self.loop].toarray()
        self.x = self.lu.solve(self.a_tl)
        schur = a_ll - self.a_tl.T @ self.x
        values, vectors = np.linalg.eigh(0.5 * (schur + schur.T))
        keep = values > RANK_RTOL * float(system.diagonal().max())
        self.vk, self.inv = vectors[:, keep], 1.0 / values[keep]
        self.ranks = np.array([int(self.tree.size + keep.sum())])
        null = vectors[:, ~keep]
        self.null = None
        if null.shape[1]:
            basis = np.zeros((m, null.shape[1]))
            basis[self.tree] = -self.x @ null
            basis[self.loop] = null
            self.null = np.linalg.qr(basis)[0]          # orthonormal basis of the null space

    def solve(self, b):
        b = b[0]
        lam = np.zeros(self.maps.m)
        y = self.lu.solve(b[self.tree])
        if self.loop.size == 0:
            lam[self.tree] = y
            return lam[None, :]
        lam_l = self.vk @ ((self.vk.T @ (b[self.loop] - self.a_tl.T @ y)) * self.inv)
        lam[self.loop] = lam_l
        lam[self.tree] = y - self.x @ lam_l
        if self.null is not None:
            # Minimum norm: remove the component along the null space of J W Jᵀ.
            lam -= self.null @ (self.null.T @ lam)
        return lam[None, :]
