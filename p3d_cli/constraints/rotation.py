"""Unit quaternions ``[w, x, y, z]`` and the rotation matrices they stand for.

A body's orientation ``q`` maps body-frame vectors to world-frame ones: ``v_world = R(q) v_body``.
A world-frame angular velocity ``ω`` rotates the body by ``exp(ω dt)`` applied on the left
(``q ← exp(ω dt / 2) ⊗ q``), because ``ω`` is expressed in the world frame. The rotation
matrix of a quaternion is ``p3d_cli.geometry.rotation.quaternion_matrix`` (here as ``quat_to_matrix``).
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.rotation import quaternion_matrix as quat_to_matrix  # noqa: F401 - the one copy
from p3d_cli.geometry.rotation import quaternion_matrix as quat_to_matrix_many  # noqa: F401 - (n, 4) at once


def quat_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p ⊗ q`` (rotate by ``q`` first, then ``p``); broadcasts over rows."""
    pw, px, py, pz = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    qw, qx, qy, qz = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([pw * qw - px * qx - py * qy - pz * qz,
                     pw * qx + px * qw + py * qz - pz * qy,
                     pw * qy - px * qz + py * qw + pz * qx,
                     pw * qz + px * qy - py * qx + pz * qw], axis=-1)


def quat_from_axis_angle(axis, angle: float) -> np.ndarray:
    """Unit quaternion of a rotation by ``angle`` radians about ``axis`` (any non-zero length)."""
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    half = 0.5 * angle
    return np.concatenate([[np.cos(half)], np.sin(half) * a])


def quat_exp(rotvec: np.ndarray) -> np.ndarray:
    """Unit quaternion of the rotation vector ``θ`` (axis ``θ/|θ|``, angle ``|θ|``); rows broadcast.

    Uses ``sin(|θ|/2)/|θ|`` through its series near zero so that tiny rotations stay exact.
    """
    rotvec = np.asarray(rotvec, dtype=np.float64)
    angle = np.linalg.norm(rotvec, axis=-1)
    half = 0.5 * angle
    small = angle < 1e-8
    safe = np.where(small, 1.0, angle)
    factor = np.where(small, 0.5 - angle * angle / 48.0, np.sin(half) / safe)
    return np.concatenate([np.cos(half)[..., None], factor[..., None] * rotvec], axis=-1)


def rotate_by(q: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """``exp(θ) ⊗ q``, renormalised: the orientation after a world-frame rotation ``θ``."""
    out = quat_multiply(quat_exp(rotvec), q)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def skew(r: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[r]ₓ`` with ``[r]ₓ v = r × v``; rows broadcast to (n, 3, 3)."""
    r = np.asarray(r, dtype=np.float64)
    out = np.zeros(r.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` for (3,) or (n, 3) arrays; ``numpy.cross`` costs ~10x more on single vectors,
    which matters in the per-constraint inner loop of stepping."""
    if a.ndim == 1 and b.ndim == 1:
        a0, a1, a2 = a.tolist()
        b0, b1, b2 = b.tolist()
        return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


# -- the same operations over many bodies in a few numpy calls (stepping's inner loop) ----------
# ``p ⊗ q = L(p) q`` with ``L(p)`` linear in ``p``: a constant linear map of the outer product.
# (Rotation matrices of many quaternions: ``quat_to_matrix``, vectorised in p3d_cli.geometry.rotation.)
_P_TO_L = np.zeros((4, 16))
for _row, _signs in enumerate((((0, 1), (1, -1), (2, -1), (3, -1)), ((1, 1), (0, 1), (3, -1), (2, 1)),
                               ((2, 1), (3, 1), (0, 1), (1, -1)), ((3, 1), (2, -1), (1, 1), (0, 1)))):
    for _col, (_k, _sign) in enumerate(_signs):
        _P_TO_L[_k, 4 * _row + _col] = _sign


def rotate_by_many(q: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """``rotate_by`` for (n, 4) quaternions and (n, 3) rotation vectors, in few numpy calls."""
    angle = np.sqrt((rotvec * rotvec).sum(axis=1))
    half = 0.5 * angle
    # sin(|θ|/2)/|θ|, through its series below 1e-8 as ``quat_exp`` does.
    factor = 0.5 - angle * angle / 48.0
    np.divide(np.sin(half), angle, out=factor, where=angle >= 1e-8)
    p = np.empty((len(q), 4))
    np.cos(half, out=p[:, 0])
    np.multiply(factor[:, None], rotvec, out=p[:, 1:])
    out = (p[:, :, None] * q[:, None, :]).reshape(-1, 16) @ _PQ_TO_PRODUCT
    return out / np.sqrt((out * out).sum(axis=1))[:, None]


# p ⊗ q as a constant linear map of the outer product p qᵀ (entry p_k q_c at 4 k + c).
_PQ_TO_PRODUCT = np.zeros((16, 4))
for _k in range(4):
    for _r in range(4):
        for _c in range(4):
            _PQ_TO_PRODUCT[4 * _k + _c, _r] = _P_TO_L[_k, 4 * _r + _c]


_NEXT, _LAST = np.array([1, 2, 0]), np.array([2, 0, 1])


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` row by row for (c, 3) arrays, in few numpy calls."""
    return a[:, _NEXT] * b[:, _LAST] - a[:, _LAST] * b[:, _NEXT]
