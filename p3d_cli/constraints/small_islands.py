"""Each island's linear algebra for ``small_step``: its dense system ``J W Jᵀ`` in numpy.

An island's rows are a dense ``(m, 6 nb)`` matrix whose pose-dependent entries are scattered in
from the joints' ``entries`` each step; ``factorise`` forms ``A = J W Jᵀ`` and its inverse (or,
on a redundant island, its pseudo-inverse), which serve the step's velocity solve and, frozen,
the next step's position correction. A one-row island (a bar) is a number, solved in floats.
"""

from __future__ import annotations

import math

import numpy as np

from p3d_cli.constraints.solver import RANK_RTOL



class _Factor:
    """One island's factorised system: ``K`` the pseudo-inverse of ``A = J W Jᵀ``, ``W Jᵀ``, and
    the position correction's gain ``W Jᵀ K``."""

    __slots__ = ("jac", "wjt", "system", "pinv", "rank", "gain")

    def __init__(self, jac, wjt, system, pinv, rank) -> None:
        self.jac, self.wjt, self.system, self.pinv, self.rank = jac, wjt, system, pinv, rank
        self.gain = wjt.dot(pinv)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Minimum-norm ``λ`` of ``A λ = b`` with one step of iterative refinement, which recovers
        the digits the factorisation's rounding loses on an ill-conditioned island (so an
        explicit (pseudo-)inverse is as accurate here as applying the factors)."""
        dot = self.pinv.dot
        lam = dot(b)
        return lam + dot(b - self.system.dot(lam))

    # Both right-hand sides carry a minus sign (``-C``, ``-J u``); every operation of the solve is
    # linear and rounds symmetrically, so solving for ``+C`` and subtracting the result is exact
    # negation, and saves a numpy call per solve.
    def correction(self, errors: list) -> np.ndarray:
        """``-W Jᵀ λ`` for ``A λ = -C``: minus the motion (6 per island body) that closes ``errors``.

        One product with the gain ``W Jᵀ K`` (one numpy call, not ``solve``'s five and a product):
        the refinement step is left out because what it recovers, the relative error
        ``~cond(A) ε`` of ``λ``, is relative to a correction of at most the drift's constraint
        error (~1e-5 of the scene's size), so ~1e-18 of the size, under the positions' own
        rounding (1e-16 of it). The impulses of the velocity solve are whole, and keep it.
        """
        return self.gain.dot(errors)

    def velocity(self, u: list):
        """``(-λ, -W Jᵀ λ)`` for ``A λ = -J u`` (``jac`` holds this step's rows only until the
        island is factorised again: the next step's correction needs the gain only)."""
        lam = self.solve(self.jac.dot(u))            # dot converts the list as np.array would
        return lam, self.wjt.dot(lam).tolist()


class _Island:
    """One island's rows as a dense ``(m, 6 nb)`` matrix whose variable entries are scattered in
    from the joints' ``entries`` each step (the ``±E`` of gap rows are set once)."""

    def __init__(self, island, joints, offsets, inv_mass) -> None:
        self.bodies = list(island.bodies)
        self.joints = [joints[k] for k in island.constraints]
        self.evaluators = [joint.evaluate for joint in self.joints]     # bound once
        self.rows = np.concatenate([np.arange(offsets[k], offsets[k + 1]) for k in island.constraints])
        m, width = len(self.rows), 6 * len(self.bodies)
        self.m = m
        column = {b: 6 * c for c, b in enumerate(self.bodies)}
        self.jac = np.zeros((m, width))
        index, first = [], 0
        for joint in self.joints:
            for body, free, sign in ((joint.a, joint.free_a, -1.0), (joint.b, joint.free_b, 1.0)):
                if not free:
                    continue
                c0 = column[body]
                index += [(first + r) * width + c0 + c for r, c in joint.columns()]
                for r, c in joint.constants:
                    self.jac[first + r, c0 + c] = sign
            first += joint.rows
        self.index = np.array(index, dtype=np.intp)
        self.weights = np.zeros((width, width))
        for c, body in enumerate(self.bodies):
            for i in range(3):
                self.weights[6 * c + i, 6 * c + i] = inv_mass[body]
        self.weight_index = np.array([(6 * c + 3 + i) * width + 6 * c + 3 + j for c in range(len(self.bodies))
                                      for i in range(3) for j in range(3)], dtype=np.intp)
        self.redundant = False
        self.flat_jac, self.flat_weights = self.jac.reshape(-1), self.weights.reshape(-1)   # views

    def errors(self, com, rot) -> list[float]:
        out: list[float] = []
        extend = out.extend
        for evaluate in self.evaluators:
            extend(evaluate(com, rot))
        return out

    def factorise(self, inv_inertia) -> _Factor:
        """``J W Jᵀ`` at the configuration of the joints' last ``evaluate``, and its inverse or
        pseudo-inverse (``_pseudo_inverse``)."""
        values: list[float] = []
        for joint in self.joints:
            values += joint.entries()
        self.flat_jac[self.index] = values
        weights: list[float] = []
        for body in self.bodies:
            weights += inv_inertia[body]
        self.flat_weights[self.weight_index] = weights
        wjt = self.weights.dot(self.jac.T)
        # J (W Jᵀ) is symmetric but for rounding, which the refinement step absorbs (the
        # eigendecomposition reads one triangle).
        system = self.jac.dot(wjt)
        pinv, rank = self._pseudo_inverse(system)
        return _Factor(self.jac, wjt, system, pinv, rank)

    def _pseudo_inverse(self, system):
        """``(A⁺, rank)`` with the rank rule of ``solver._DenseStack``: eigenvalues below
        ``RANK_RTOL ×`` the largest diagonal entry count as zero.

        The eigendecomposition costs 2-3 times an inverse, so an island is first inverted:
        ``‖A⁻¹‖_F >= ‖A⁻¹‖₂ = 1/λ_min``, so ``‖A⁻¹‖_F RANK_RTOL d < 1/2`` proves every
        eigenvalue is above twice the threshold (its rounding is far smaller), and the inverse
        is the pseudo-inverse. Otherwise (a redundant island, which stays so: it is not tried
        again), the eigendecomposition decides.
        """
        # Python's max of the diagonal as a list is numpy's max (a third of the time) when the
        # entries are finite; with a nan either gives a certificate that fails (the inverse is not
        # finite then), and the eigendecomposition raises.
        threshold = RANK_RTOL * max(max(system.diagonal().tolist()), 0.0)
        if not self.redundant:
            try:
                inverse = np.linalg.inv(system)
            except np.linalg.LinAlgError:
                inverse = None
            if inverse is not None and threshold > 0 and math.sqrt(float(np.vdot(inverse, inverse))) * threshold < 0.5:
                return inverse, self.m
            self.redundant = True
        eig, vectors = np.linalg.eigh(system)   # its lower triangle; LinAlgError if it does not converge
        keep = eig > threshold
        inv = np.divide(1.0, eig, out=np.zeros_like(eig), where=keep)
        return (vectors * inv).dot(vectors.T), int(keep.sum())


class _Single:
    """An island of one row (a bar) in floats: its system is the number ``a = J W Jᵀ``.

    Same rules as ``_Island``: rank 1 when ``a > RANK_RTOL a``, one refinement step.
    """

    def __init__(self, island, joints, offsets, inv_mass) -> None:
        self.joint = joints[island.constraints[0]]
        self.bodies = list(island.bodies)
        self.rows = np.array([offsets[island.constraints[0]]])
        self.m = 1
        self.inv_mass = [inv_mass[b] for b in self.bodies]

    def errors(self, com, rot) -> list[float]:
        return self.joint.evaluate(com, rot)

    def factorise(self, inv_inertia) -> "_SingleFactor":
        row = self.joint.entries()          # 6 per free side, the free sides in body order
        if self.joint.free_a and self.joint.free_b and self.joint.a > self.joint.b:
            row = row[6:] + row[:6]
        wjt: list[float] = []
        for c, body in enumerate(self.bodies):
            j0, j1, j2, j3, j4, j5 = row[6 * c:6 * c + 6]
            im, w = self.inv_mass[c], inv_inertia[body]
            wjt += [im * j0, im * j1, im * j2, w[0] * j3 + w[1] * j4 + w[2] * j5,
                    w[3] * j3 + w[4] * j4 + w[5] * j5, w[6] * j3 + w[7] * j4 + w[8] * j5]
        # Plain sums, not math.fsum, which raises on an overflow that must reach the checks as inf.
        a = sum([j * w for j, w in zip(row, wjt)])
        keep = a > RANK_RTOL * max(a, 0.0)
        if not math.isfinite(a):
            raise np.linalg.LinAlgError("the constraint system is not finite")
        return _SingleFactor(row, wjt, a, 1.0 / a if keep else 0.0, int(keep))


class _SingleFactor:
    __slots__ = ("row", "wjt", "system", "pinv", "rank")

    def __init__(self, row, wjt, system, pinv, rank) -> None:
        self.row, self.wjt, self.system, self.pinv, self.rank = row, wjt, system, pinv, rank

    def _solve(self, b: float) -> float:
        lam = self.pinv * b
        return lam + self.pinv * (b - self.system * lam)

    def correction(self, errors: list) -> tuple:
        lam = self._solve(errors[0])
        return tuple([w * lam for w in self.wjt])

    def velocity(self, u: list):
        lam = self._solve(sum([j * v for j, v in zip(self.row, u)]))
        return np.array([lam]), [w * lam for w in self.wjt]
