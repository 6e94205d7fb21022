"""The closed test's open verdicts: proven from the sorted keys, or confirmed exactly."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from helpers.meshes import cube_triangles
from p3d_cli.io.source import array_source
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.closed import (closed_exact, column_edge_keys, doubtful_edges, keys_pair_up,
                                 sides_pair_up_exactly)
from p3d_cli.mesh.columns import columns


def sorted_keys(t):
    keys = column_edge_keys(columns(np.asarray(t, dtype=float)))
    keys.sort()
    return keys


def test_one_boundary_edge_is_proof_of_openness():
    keys = sorted_keys(cube_triangles()[1:])
    assert not keys_pair_up(keys)
    assert doubtful_edges(keys).size == 0


def test_balanced_groups_of_four_are_doubtful_and_settled_exactly():
    t = cube_triangles()
    # Face 0 twice more, once each way: its edges have four balanced uses (non-manifold).
    doubled = np.concatenate([t, t[:1], t[:1, ::-1]])
    keys = sorted_keys(doubled)
    doubtful = doubtful_edges(keys)
    assert doubtful.size == 3
    blocks = [doubled[:5], doubled[5:]]
    assert sides_pair_up_exactly(blocks, doubtful) is False
    assert closed_exact(doubled) is False


def test_exact_pairing_accepts_a_closed_mesh_whatever_the_keys_said():
    # As after a collision: every edge of a closed cube handed to the exact comparison.
    t = cube_triangles()
    keys = sorted_keys(t)
    every_edge = np.unique(keys >> np.uint64(1))
    assert sides_pair_up_exactly([t[:7], t[7:]], every_edge) is True
    assert sides_pair_up_exactly([t[:7], t[7:, ::-1]], every_edge) is False


def test_negative_zero_pairs_with_zero_in_the_exact_comparison():
    t = cube_triangles()
    t[:6][t[:6] == 0.0] = -0.0
    every_edge = np.unique(sorted_keys(t) >> np.uint64(1))
    assert sides_pair_up_exactly([t], every_edge) is True


@given(st.integers(0, 2**32 - 1), st.integers(1, 40))
def test_analyze_closed_flag_agrees_with_exact_test(seed, n):
    rng = np.random.default_rng(seed)
    pts = rng.integers(0, 3, size=(5, 3)).astype(float)
    t = pts[rng.integers(0, 5, size=(n, 3))]
    t = np.concatenate([t, t[::-1, ::-1]])  # often balanced: the doubtful path runs
    found = analyze(array_source("test", t, "float64"), "test")
    assert found.closed == closed_exact(t)


def test_check_source_with_a_wrong_face_count_is_a_format_error():
    import pytest

    from p3d_cli.errors import FormatError
    from p3d_cli.io.source import MeshSource
    from p3d_cli.mesh.verdicts import check_source

    t = cube_triangles()
    for count in (11, 13):
        mesh = MeshSource("stl-binary", count, "float64", lambda: iter([t[:6], t[6:]]))
        with pytest.raises(FormatError, match=f"expected {count} faces"):
            check_source(mesh, "cube.stl")
