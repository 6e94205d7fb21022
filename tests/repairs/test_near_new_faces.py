"""``near_new_faces``: the faces whose boxes may meet a new face's, never missing one."""

from __future__ import annotations

import numpy as np
import pytest

from p3d_cli.repairs.solidity import near_new_faces


def meeting(points: np.ndarray, faces: np.ndarray, new: np.ndarray) -> np.ndarray:
    """Brute force: every face whose box meets the box of a face in ``new``."""
    corners = points[faces]
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    meets = ((lo[:, None, :] <= hi[None, new, :]) & (lo[None, new, :] <= hi[:, None, :])).all(axis=2)
    return np.flatnonzero(meets.any(axis=1))


@pytest.mark.parametrize("seed", range(6))
def test_every_face_whose_box_meets_a_new_face_is_kept(seed):
    rng = np.random.default_rng(seed)
    n = 2000
    base = rng.random((n, 3)) * 20 * 10.0 ** rng.integers(-3, 4) + rng.normal(size=3) * 1e3
    spread = 0.3 * (1 + seed) * (base.max() - base.min()) / 20
    points = np.concatenate([base, base + rng.normal(size=(n, 3)) * spread, base + rng.normal(size=(n, 3)) * spread])
    faces = np.stack([np.arange(n), np.arange(n) + n, np.arange(n) + 2 * n], axis=1)
    if seed % 2:
        faces[:50] = faces[:50, [0, 0, 1]]                  # degenerate boxes: lines
    new = rng.choice(n, 40, replace=False)
    kept = near_new_faces(points, faces, new)
    assert np.all(np.diff(kept) > 0)
    assert set(meeting(points, faces, new).tolist()) <= set(kept.tolist())
    assert set(new.tolist()) <= set(kept.tolist())


def test_small_holes_over_a_large_mesh_keep_only_their_neighbours():
    """Small faces spread far apart keep a few faces each, not the whole mesh (the one box
    around all the new faces would take in every face)."""
    u = v = 200
    x, y = np.meshgrid(np.arange(u + 1, dtype=np.float64), np.arange(v + 1, dtype=np.float64), indexing="ij")
    points = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    at = (np.arange(u)[:, None] * (v + 1) + np.arange(v)[None, :]).ravel()
    faces = np.concatenate([np.stack([at, at + v + 1, at + 1], 1), np.stack([at + 1, at + v + 1, at + v + 2], 1)])
    new = np.arange(0, len(faces), 997)
    kept = near_new_faces(points, faces, new)
    assert set(meeting(points, faces, new).tolist()) <= set(kept.tolist())
    assert len(kept) < 0.05 * len(faces)
