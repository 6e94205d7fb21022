"""Solving the design note's eq. 20 for constraint impulses, island by island.

With ``J`` the stacked constraint rows (each constraint's ``ME`` blocks, FACTS.md signs) and
``W = M⁻¹`` the block-diagonal inverse mass (``m⁻¹ E`` and the world inverse inertia
``R I⁻¹ Rᵀ``; zero for fixed bodies), eq. 20 is ``(J W Jᵀ) λ = b``: for a velocity solve
``b = -J u`` (the velocity error of eq. 19), for a position correction ``b = -C``. ``J W Jᵀ`` is
symmetric positive semi-definite; it is singular exactly when constraints are redundant (a
closed loop, a constraint given twice). Then ``λ`` is the minimum-norm solution and the rank
is reported; the resulting motion ``W Jᵀ λ`` is the same for every solution, because it is the
mass-weighted projection onto the motions the constraints allow.

Small islands: a dense eigendecomposition (pseudo-inverse with a relative tolerance).
Large islands: a sparse LU factorisation of the spanning-forest block, which is positive
definite (see ``islands``), and a dense Schur complement for the few loop-closing rows, whose
eigendecomposition gives the rank; the minimum-norm ``λ`` is then the particular solution
minus its projection on the null space ``[-A_TT⁻¹ A_TL Z; Z]``. A chain is banded, so its
factorisation costs time linear in its length.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Islands with at most this many equations are solved densely.
DENSE_LIMIT = 240
#: An eigenvalue below this fraction of the largest diagonal entry of ``J W Jᵀ`` counts as
#: zero (a redundant direction). The system's entries are ``1/mass`` and ``r²/inertia`` sized,
#: so the diagonal is its natural scale; 1e-9 sits far above rounding (~1e-16 relative) and
#: far below any physically meaningful stiffness ratio.
RANK_RTOL = 1e-9


@dataclass(frozen=True)
class ImpulseSolution:
    """Multipliers of every constraint and what the solve learned about the system.

    Attributes
    ----------
    multipliers : tuple of (k,) float64
        One array per constraint, scene order.
    rank : int
        Rank of ``J W Jᵀ`` summed over islands.
    equations : int
        Number of rows.
    island_ranks : tuple of (int, int)
        ``(rank, equations)`` per island.
    """

    multipliers: tuple[np.ndarray, ...]
    rank: int
    equations: int
    island_ranks: tuple[tuple[int, int], ...]


def solve_impulses(islands, pairs, blocks, inv_mass, inv_inertia, rhs,
                   dense_limit: int = DENSE_LIMIT) -> ImpulseSolution:
    """Minimum-norm multipliers of ``(J W Jᵀ) λ = b``, island by island.

    Parameters
    ----------
    islands : sequence of Island
    pairs : sequence of (int, int)
        Body indices of each constraint.
    blocks : sequence of ((k, 6), (k, 6)) float64
        ``(J_a, J_b)`` of each constraint.
    inv_mass : (n,) float64
        Zero for fixed bodies.
    inv_inertia : (n, 3, 3) float64
        World-frame inverse inertia; zero for fixed bodies.
    rhs : sequence of (k,) float64
        ``b`` of each constraint.
    dense_limit : int
        Islands with more equations take the sparse path.
    """
    out: list[np.ndarray | None] = [None] * len(pairs)
    rank = equations = 0
    per_island = []
    for island in islands:
        sizes = [len(rhs[k]) for k in island.constraints]
        m = sum(sizes)
        if m <= dense_limit:
            lam, r = _dense(island, pairs, blocks, inv_mass, inv_inertia, rhs)
        else:
            lam, r = _sparse(island, pairs, blocks, inv_mass, inv_inertia, rhs)
        start = 0
        for k, size in zip(island.constraints, sizes):
            out[k] = lam[start:start + size]
            start += size
        rank += r
        equations += m
        per_island.append((r, m))
    return ImpulseSolution(tuple(out), rank, equations, tuple(per_island))


def body_changes(pairs, blocks, multipliers, inv_mass, inv_inertia) -> tuple[np.ndarray, np.ndarray]:
    """``W Jᵀ λ`` split into linear and angular parts per body.

    Returns
    -------
    dv, dw : (n, 3) float64
        Change of centre-of-mass velocity (or displacement) and of angular velocity (or
        rotation vector), world frame; zero for fixed bodies.
    """
    n = len(inv_mass)
    force = np.zeros((n, 6))
    for (a, b), (ja, jb), lam in zip(pairs, blocks, multipliers):
        force[a] += ja.T @ lam
        force[b] += jb.T @ lam
    dv = inv_mass[:, None] * force[:, :3]
    dw = np.einsum("nij,nj->ni", inv_inertia, force[:, 3:])
    return dv, dw


def _local_rows(island, pairs, blocks, rhs):
    """Row offsets and local body numbering of one island."""
    local = {body: i for i, body in enumerate(island.bodies)}
    offsets = np.cumsum([0] + [len(rhs[k]) for k in island.constraints])
    return local, offsets


def _dense(island, pairs, blocks, inv_mass, inv_inertia, rhs):
    local, offsets = _local_rows(island, pairs, blocks, rhs)
    m, nb = int(offsets[-1]), len(island.bodies)
    jac = np.zeros((m, nb, 6))
    for row, k in zip(offsets, island.constraints):
        a, b = pairs[k]
        ja, jb = blocks[k]
        size = len(rhs[k])
        if a in local:
            jac[row:row + size, local[a]] += ja
        if b in local:
            jac[row:row + size, local[b]] += jb
    idx = np.array(island.bodies)
    weighted = np.empty_like(jac)
    weighted[:, :, :3] = jac[:, :, :3] * inv_mass[idx][None, :, None]
    weighted[:, :, 3:] = np.einsum("mbj,bjk->mbk", jac[:, :, 3:], inv_inertia[idx])
    system = jac.reshape(m, -1) @ weighted.reshape(m, -1).T
    system = 0.5 * (system + system.T)
    b = np.concatenate([rhs[k] for k in island.constraints])
    values, vectors = np.linalg.eigh(system)
    tol = RANK_RTOL * max(float(np.max(np.diag(system))), 0.0)
    keep = values > tol
    basis, scale = vectors[:, keep], values[keep]
    lam = basis @ ((basis.T @ b) / scale)
    # One step of iterative refinement: the eigendecomposition's rounding grows with the
    # condition number; re-solving for the residual recovers the lost digits.
    lam += basis @ ((basis.T @ (b - system @ lam)) / scale)
    return lam, int(keep.sum())


def _sparse(island, pairs, blocks, inv_mass, inv_inertia, rhs):
    import scipy.sparse as sp
    from scipy.sparse.linalg import splu

    local, offsets = _local_rows(island, pairs, blocks, rhs)
    m, nb = int(offsets[-1]), len(island.bodies)
    rows, cols, data = [], [], []
    for row, k in zip(offsets, island.constraints):
        a, b = pairs[k]
        size = len(rhs[k])
        for body, block in ((a, blocks[k][0]), (b, blocks[k][1])):
            if body in local:
                rows.append(row + _ROW_PATTERN[size])
                cols.append(6 * local[body] + _COL_PATTERN[size])
                data.append(block.ravel())
    jac = sp.csr_matrix((np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(m, 6 * nb))
    idx = np.array(island.bodies)
    w_blocks = np.zeros((nb, 6, 6))
    w_blocks[:, [0, 1, 2], [0, 1, 2]] = inv_mass[idx][:, None]
    w_blocks[:, 3:, 3:] = inv_inertia[idx]
    weights = _block_diag(w_blocks)
    system = (jac @ weights @ jac.T).tocsc()
    b = np.concatenate([rhs[k] for k in island.constraints])
    loop_rows = np.zeros(m, dtype=bool)
    for row, k, loop in zip(offsets, island.constraints, island.loop):
        if loop:
            loop_rows[row:row + len(rhs[k])] = True
    tree_idx, loop_idx = np.flatnonzero(~loop_rows), np.flatnonzero(loop_rows)
    a_tt = system[tree_idx][:, tree_idx].tocsc()
    # The spanning-forest block is symmetric positive definite: a symmetric ordering with no
    # pivoting keeps a banded (chain) or tree structure sparse.
    lu = splu(a_tt, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    lam = np.zeros(m)
    if loop_idx.size == 0:
        lam[tree_idx] = lu.solve(b[tree_idx])
        return lam, m
    a_tl = system[tree_idx][:, loop_idx].toarray()
    a_ll = system[loop_idx][:, loop_idx].toarray()
    x = lu.solve(a_tl)
    schur = a_ll - a_tl.T @ x
    schur = 0.5 * (schur + schur.T)
    y = lu.solve(b[tree_idx])
    values, vectors = np.linalg.eigh(schur)
    tol = RANK_RTOL * float(system.diagonal().max())
    keep = values > tol
    rhs_l = b[loop_idx] - a_tl.T @ y
    lam_l = vectors[:, keep] @ ((vectors[:, keep].T @ rhs_l) / values[keep])
    lam[loop_idx] = lam_l
    lam[tree_idx] = y - x @ lam_l
    null = vectors[:, ~keep]
    if null.shape[1]:
        basis = np.zeros((m, null.shape[1]))
        basis[tree_idx] = -x @ null
        basis[loop_idx] = null
        coef, *_ = np.linalg.lstsq(basis, lam, rcond=None)
        lam = lam - basis @ coef
    return lam, int(tree_idx.size + keep.sum())


#: Row and column offsets of a (k, 6) block's entries in row-major order, per k.
_ROW_PATTERN = {k: np.repeat(np.arange(k), 6) for k in range(1, 7)}
_COL_PATTERN = {k: np.tile(np.arange(6), k) for k in range(1, 7)}


def _block_diag(w_blocks):
    """Block-diagonal sparse matrix of (nb, 6, 6) blocks, built in one go (linear time)."""
    import scipy.sparse as sp

    nb = len(w_blocks)
    return sp.bsr_matrix((w_blocks, np.arange(nb), np.arange(nb + 1)), shape=(6 * nb, 6 * nb)).tocsr()
