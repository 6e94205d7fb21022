"""A frozen copy of the stepping algorithm as it was before the array-based step (commit 1141c9c).



The oracle for ``test_stepping_reference``: ``world``, ``solver``, ``islands``, ``joint`` and the

three constraint types of that commit, concatenated with their imports merged, and the stepping

loop of ``simulation.solve_scene``. It builds every constraint row in a Python loop and

re-solves the system at every position-correction iteration; slow, but the numbers the new

step must reproduce. Do not "fix" it: it is the reference.

"""



from __future__ import annotations



from collections import deque

from dataclasses import dataclass

from types import SimpleNamespace



import numpy as np



from p3d_cli.constraints.bodies import resolve_inertials

from p3d_cli.constraints.rotation import cross, quat_to_matrix, rotate_by, skew

from p3d_cli.errors import SceneError



# ---- joint.py ------------------------------------------------------------

@dataclass(frozen=True)
class JointGeometry:
    """World-frame geometry of one constraint.

    Attributes
    ----------
    r_a, r_b : (3,) float64
        Attachment point minus centre of mass, world frame.
    p_a, p_b : (3,) float64
        Attachment points, world frame.
    z_a, z_b : (3,) float64 or None
        Unit hinge axes, world frame.
    where : str
        The constraint's place in the scene, for messages.
    """

    r_a: np.ndarray
    r_b: np.ndarray
    p_a: np.ndarray
    p_b: np.ndarray
    z_a: np.ndarray | None = None
    z_b: np.ndarray | None = None
    where: str = ""


def joint_geometry(spec, com_a, rot_a, com_body_a, com_b, rot_b, com_body_b) -> JointGeometry:
    """World geometry of constraint ``spec`` for bodies at the given poses.

    Parameters
    ----------
    spec : ConstraintSpec
    com_a, com_b : (3,) float64
        World centres of mass.
    rot_a, rot_b : (3, 3) float64
        Body-to-world rotations.
    com_body_a, com_body_b : (3,) float64
        Centres of mass in the body frames.
    """
    r_a = rot_a @ (spec.attach_a - com_body_a)
    r_b = rot_b @ (spec.attach_b - com_body_b)
    z_a = z_b = None
    if spec.axis_a is not None:
        z_a, z_b = rot_a @ spec.axis_a, rot_b @ spec.axis_b
    return JointGeometry(r_a, r_b, com_a + r_a, com_b + r_b, z_a, z_b, spec.where)



# ---- ball.py ------------------------------------------------------------

_BALL_EQUATIONS = 3


def _ball_jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (3, 6): rows of ``J_a u_a + J_b u_b`` with ``u = (v, ω)``."""
    ja, jb = np.zeros((3, 6)), np.zeros((3, 6))
    jb[:, :3] = _BALL_EYE
    jb[:, 3:] = -skew(geo.r_b)
    ja[:, :3] = -_BALL_EYE
    ja[:, 3:] = skew(geo.r_a)
    return ja, jb


_BALL_EYE = np.eye(3)


def _ball_position_error(spec, geo) -> np.ndarray:
    """(3,) ``p_b - p_a``: the gap between the two attachment points."""
    return geo.p_b - geo.p_a


def _ball_impulse(geo, lam: np.ndarray) -> dict:
    """The impulse on body ``b`` (world frame)."""
    return {"impulse": lam.copy()}


ball = SimpleNamespace(jacobian=_ball_jacobian, position_error=_ball_position_error, impulse=_ball_impulse)



# ---- hinge.py ------------------------------------------------------------

_HINGE_EQUATIONS = 5


def _hinge_frame(geo) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``(x, y, z, s)``: an orthonormal frame with ``z`` the hinge axis, and the flip ``s`` of ``z_b``."""
    s = 1.0 if float(geo.z_a @ geo.z_b) >= 0 else -1.0
    z = geo.z_a + s * geo.z_b
    norm = np.linalg.norm(z)
    # Axes at exactly 90° still bisect; only an exactly opposite pair (impossible after the flip)
    # would leave z undefined.
    z = z / norm if norm > 0 else geo.z_a
    # x: the world axis least aligned with z, made perpendicular (deterministic and well
    # conditioned: |x| >= sqrt(2/3) before normalising).
    seed = np.zeros(3)
    seed[int(np.argmin(np.abs(z)))] = 1.0
    x = seed - (seed @ z) * z
    x /= np.linalg.norm(x)
    y = cross(z, x)
    return x, y, z, s


def _hinge_jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (5, 6)."""
    x, y, _, _ = _hinge_frame(geo)
    ja_ball, jb_ball = _ball_jacobian(geo)
    angular = np.zeros((2, 6))
    angular[0, 3:], angular[1, 3:] = x, y
    return np.vstack([ja_ball, -angular]), np.vstack([jb_ball, angular])


def _hinge_position_error(spec, geo) -> np.ndarray:
    """(5,): the attachment gap, then the axis misalignment ``(z_a × s z_b)`` along ``x`` and ``y``."""
    x, y, _, s = _hinge_frame(geo)
    tilt = cross(geo.z_a, s * geo.z_b)
    return np.concatenate([geo.p_b - geo.p_a, [tilt @ x, tilt @ y]])


def _hinge_impulse(geo, lam: np.ndarray) -> dict:
    """Linear and angular impulse on body ``b`` (world frame)."""
    x, y, _, _ = _hinge_frame(geo)
    return {"impulse": lam[:3].copy(), "angular_impulse": lam[3] * x + lam[4] * y}


hinge = SimpleNamespace(jacobian=_hinge_jacobian, position_error=_hinge_position_error, impulse=_hinge_impulse)



# ---- bar.py ------------------------------------------------------------

_BAR_EQUATIONS = 1


def _bar_direction(geo) -> np.ndarray:
    """Unit vector from ``p_a`` to ``p_b``.

    Raises
    ------
    SceneError
        The points coincide: a bar of zero length has no direction.
    """
    d = geo.p_b - geo.p_a
    norm = float(np.linalg.norm(d))
    if norm == 0.0:
        raise SceneError(geo.where or "bar", "the attachment points have come together, so the bar has "
                         "no direction", "use a ball joint to join two points, or a smaller --dt")
    return d / norm


def _bar_jacobian(geo) -> tuple[np.ndarray, np.ndarray]:
    """``(J_a, J_b)``, each (1, 6)."""
    d = _bar_direction(geo)
    jb = np.concatenate([d, cross(geo.r_b, d)])[None, :]
    ja = -np.concatenate([d, cross(geo.r_a, d)])[None, :]
    return ja, jb


def _bar_position_error(spec, geo) -> np.ndarray:
    """(1,): the distance between the points minus the bar's length."""
    return np.array([np.linalg.norm(geo.p_b - geo.p_a) - spec.length])


def _bar_impulse(geo, lam: np.ndarray) -> dict:
    """The impulse on ``b`` along the bar (scalar) and as a world vector."""
    return {"impulse": float(lam[0]), "impulse_vector": lam[0] * _bar_direction(geo)}


bar = SimpleNamespace(jacobian=_bar_jacobian, position_error=_bar_position_error, impulse=_bar_impulse)



# ---- islands.py ------------------------------------------------------------

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



# ---- solver.py ------------------------------------------------------------

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



# ---- world.py ------------------------------------------------------------

class World:
    """Arrays over the scene's bodies (scene order) and its constraints."""

    def __init__(self, scene, inertials: dict, dense_limit: int = DENSE_LIMIT) -> None:
        n = len(scene.bodies)
        self.scene = scene
        self.dense_limit = dense_limit
        self.index = {b.name: i for i, b in enumerate(scene.bodies)}
        self.fixed = np.array([b.fixed for b in scene.bodies], dtype=bool)
        self.active = np.array([(not b.fixed) and b.name in inertials for b in scene.bodies], dtype=bool)
        self.known = np.array([b.name in inertials for b in scene.bodies], dtype=bool)
        self.mass = np.zeros(n)
        self.inertia_body = np.zeros((n, 3, 3))
        self.inv_inertia_body = np.zeros((n, 3, 3))
        self.com_body = np.zeros((n, 3))
        for i, body in enumerate(scene.bodies):
            inertial = inertials.get(body.name)
            if inertial is None:
                continue
            self.com_body[i] = inertial.center_of_mass
            if self.active[i]:
                self.mass[i] = inertial.mass
                self.inertia_body[i] = inertial.inertia
                self.inv_inertia_body[i] = np.linalg.inv(inertial.inertia)
        self.inv_mass = np.where(self.active, 1.0 / np.where(self.active, self.mass, 1.0), 0.0)
        self.quat = np.array([b.rotation for b in scene.bodies]).reshape(n, 4)
        self.rot = quat_to_matrix(self.quat)
        origins = np.array([b.position for b in scene.bodies]).reshape(n, 3)
        self.com = origins + np.einsum("nij,nj->ni", self.rot, self.com_body)
        self.vel = np.array([b.velocity for b in scene.bodies]).reshape(n, 3) * self.active[:, None]
        self.omega = np.array([b.angular_velocity for b in scene.bodies]).reshape(n, 3) * self.active[:, None]
        self.pairs = [(self.index[c.a], self.index[c.b]) for c in scene.constraints]
        self.modules = [CONSTRAINT_TYPES[c.type] for c in scene.constraints]
        self.islands = find_islands(self.pairs, ~self.active)
        self.island_of = {}
        for number, island in enumerate(self.islands):
            for k in island.constraints:
                self.island_of[k] = number
        self.constrained = np.zeros(n, dtype=bool)
        for a, b in self.pairs:
            self.constrained[a] = self.constrained[b] = True
        self._update_inverse_inertia()

    # -- derived quantities -------------------------------------------------------------
    def _update_inverse_inertia(self) -> None:
        self.rot = quat_to_matrix(self.quat)
        self.inv_inertia = self.rot @ self.inv_inertia_body @ np.transpose(self.rot, (0, 2, 1))

    def inertia_world(self) -> np.ndarray:
        return self.rot @ self.inertia_body @ np.transpose(self.rot, (0, 2, 1))

    def origins(self) -> np.ndarray:
        """World positions of the body frames' origins, (n, 3)."""
        return self.com - np.einsum("nij,nj->ni", self.rot, self.com_body)

    def geometries(self) -> list:
        out = []
        for spec, (a, b) in zip(self.scene.constraints, self.pairs):
            out.append(joint_geometry(spec, self.com[a], self.rot[a], self.com_body[a],
                                      self.com[b], self.rot[b], self.com_body[b]))
        return out

    def kinetic_energy(self) -> float:
        linear = 0.5 * np.sum(self.mass * np.sum(self.vel ** 2, axis=1))
        angular = 0.5 * np.einsum("ni,nij,nj->", self.omega, self.inertia_world(), self.omega)
        return float(linear + angular)

    def momentum(self) -> np.ndarray:
        return np.sum(self.mass[:, None] * self.vel, axis=0)

    def angular_momentum(self) -> np.ndarray:
        """About the world origin: ``Σ m x × v + I_world ω``."""
        orbital = np.cross(self.com, self.mass[:, None] * self.vel)
        spin = np.einsum("nij,nj->ni", self.inertia_world(), self.omega)
        return np.sum(orbital + spin, axis=0)

    # -- the two projections ------------------------------------------------------------
    def _blocks(self, geos) -> list:
        return [module.jacobian(geo) for module, geo in zip(self.modules, geos)]

    def velocity_residuals(self, geos, blocks) -> list:
        u = np.hstack([self.vel, self.omega])
        return [ja @ u[a] + jb @ u[b] for (a, b), (ja, jb) in zip(self.pairs, blocks)]

    def position_residuals(self, geos) -> list:
        return [module.position_error(spec, geo)
                for module, spec, geo in zip(self.modules, self.scene.constraints, geos)]

    def solve_velocities(self):
        """One velocity solve (eq. 20): apply the impulses that make every constraint's velocity
        equations hold. Returns ``(solution, geometries)``."""
        geos = self.geometries()
        blocks = self._blocks(geos)
        rhs = [-r for r in self.velocity_residuals(geos, blocks)]
        solution = solve_impulses(self.islands, self.pairs, blocks, self.inv_mass, self.inv_inertia, rhs,
                                  self.dense_limit)
        dv, dw = body_changes(self.pairs, blocks, solution.multipliers, self.inv_mass, self.inv_inertia)
        self.vel += dv
        self.omega += dw
        return solution, geos

    def correct_positions(self, tolerance: float, frozen=None, iterations: int = 8):
        """Position projection onto ``C(x) = 0`` along mass-weighted constraint directions.

        Parameters
        ----------
        tolerance : float
            Stop once every position error is at most this.
        frozen : (blocks, inv_inertia), optional
            Constraint rows and world inverse inertia taken at the start of a time step. The
            displacement is then ``W₀ J₀ᵀ λ`` with ``λ`` found by iterating
            ``(J₀ W₀ J₀ᵀ) Δλ = -C(x)`` (SHAKE's frozen-gradient projection, which RATTLE needs
            to be symplectic; it converges at a rate of order ``ω dt`` per iteration).
            Without it, each iteration re-linearises at the current positions (Newton), which
            is what assembling a scene needs.
        iterations : int

        Returns
        -------
        worst : float
            The largest remaining position error.
        dx, dtheta : (n, 3) float64
            Total displacement of each centre of mass and rotation vector applied.
        """
        n = len(self.mass)
        total_dx, total_dtheta = np.zeros((n, 3)), np.zeros((n, 3))
        for _ in range(iterations):
            geos = self.geometries()
            errors = self.position_residuals(geos)
            worst = max((float(np.abs(e).max()) for e in errors), default=0.0)
            if worst <= tolerance:
                return worst, total_dx, total_dtheta
            blocks, inv_inertia = frozen if frozen is not None else (self._blocks(geos), self.inv_inertia)
            solution = solve_impulses(self.islands, self.pairs, blocks, self.inv_mass, inv_inertia,
                                      [-e for e in errors], self.dense_limit)
            dx, dtheta = body_changes(self.pairs, blocks, solution.multipliers, self.inv_mass, inv_inertia)
            self.com += dx
            self.quat = rotate_by(self.quat, dtheta)
            self._update_inverse_inertia()
            total_dx += dx
            total_dtheta += dtheta
        worst = max((float(np.abs(e).max()) for e in self.position_residuals(self.geometries())), default=0.0)
        return worst, total_dx, total_dtheta

    def frozen_rows(self):
        """Constraint rows and world inverse inertia now, for ``correct_positions(frozen=...)``."""
        return self._blocks(self.geometries()), self.inv_inertia.copy()

    def drift(self, dt: float) -> None:
        """Advance positions and orientations by ``dt`` at the current velocities.

        The orientation turns by ``exp(ω dt)`` (unit quaternions, renormalised). Each free
        body's angular momentum ``I_world ω`` is kept through the turn, so ``ω`` follows the
        rotated inertia (torque-free motion of an asymmetric body is not lost).
        """
        moving = self.active
        spin = np.einsum("nij,nj->ni", self.inertia_world(), self.omega)
        self.com[moving] += self.vel[moving] * dt
        self.quat[moving] = rotate_by(self.quat[moving], self.omega[moving] * dt)
        self._update_inverse_inertia()
        self.omega[moving] = np.einsum("nij,nj->ni", self.inv_inertia, spin)[moving]



CONSTRAINT_TYPES = {"ball": ball, "hinge": hinge, "bar": bar}


# ---- simulation.py: the stepping loop of solve_scene ---------------------------------

def legacy_step(scene, steps: int, dt: float, on_step=None, dense_limit: int = DENSE_LIMIT):
    """Run the old RATTLE loop; ``on_step(step, world)`` after each step. Returns the world.

    Every body's mass properties are resolved (as a trajectory run does), so the world's
    arrays cover the same bodies as ``solve_scene(..., on_step=...)``.
    """
    inertials = resolve_inertials(list(scene.bodies), ".")
    world = World(scene, inertials, dense_limit)
    scale = 1.0
    for c in scene.constraints:
        scale = max(scale, float(np.abs(c.attach_a).max()), float(np.abs(c.attach_b).max()))
    tolerance = 1e-12 * scale
    half_kick = 0.5 * dt * scene.gravity
    worst, _, _ = world.correct_positions(tolerance)
    solution, _ = world.solve_velocities()
    for step in range(1, steps + 1):
        frozen = world.frozen_rows()
        world.vel[world.active] += half_kick
        world.drift(dt)
        error, dx, dtheta = world.correct_positions(tolerance, frozen)
        world.vel += dx / dt
        world.omega += dtheta / dt
        worst = max(worst, error)
        world.vel[world.active] += half_kick
        solution, _ = world.solve_velocities()
        if on_step is not None:
            on_step(step, world)
    world.solution, world.worst = solution, worst
    return world
