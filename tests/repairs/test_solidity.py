"""The exact tests repair takes from p3d check, as the steps use them, against slow oracles:
the weld's groups against every pair compared, the nesting of boxes against their boxes."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from helpers.repair_oracles import box_nesting, brute_weld
from p3d_cli.repairs.solidity import nesting_depths, weld_points


@given(st.integers(0, 2**32 - 1), st.floats(1e-3, 0.3))
def test_weld_groups_are_every_pair_within_the_tolerance_joined(seed, tolerance):
    points = np.random.default_rng(seed).uniform(0, 1, (40, 3))
    target, _ = weld_points(points, tolerance)
    expected, _ = brute_weld(points, tolerance)
    # Same groups (the numbering of a group may differ): equal labels exactly together.
    same = target[:, None] == target[None, :]
    assert np.array_equal(same, expected[:, None] == expected[None, :])


def box(lo: float, hi: float, inward: bool) -> np.ndarray:
    from helpers.meshes import CUBE_FACES, CUBE_VERTICES

    triangles = (CUBE_VERTICES * (hi - lo) + lo)[CUBE_FACES]
    return triangles[:, [0, 2, 1]] if inward else triangles


def test_nesting_depths_of_boxes_in_boxes():
    shells = [box(0, 10, False), box(1, 9, True), box(2, 8, False), box(20, 21, False)]
    triangles = np.concatenate(shells)
    points, faces = np.unique(triangles.reshape(-1, 3), axis=0, return_inverse=True)
    faces = faces.reshape(-1, 3)
    labels = np.repeat(np.arange(4), 12)
    depth = nesting_depths(points, faces, labels, 4, np.arange(4))
    assert depth == box_nesting(points, faces, labels, 4, np.arange(4)) == {0: 0, 1: 1, 2: 2, 3: 0}
