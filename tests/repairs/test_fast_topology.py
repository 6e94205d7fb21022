"""``p3d repair`` from the topology's fast path: a mesh whose only problem edges are boundary
edges is found by ``p3d_cli.mesh.paired`` (its layout lists the boundary sides alone,
``edges.lone_sides``), and its repair must be the general path's, output and report alike:
the fast path numbers the vertices otherwise, and nothing the steps do may depend on it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from helpers.kernels import numpy_road
from helpers.tori import grid_torus
from helpers.topology import fast_path_refused, real_surface_meshes
import p3d_cli.mesh.paired as paired
import p3d_cli.mesh.topology as topo
from p3d_cli.mesh.topology import _array_blocks
from p3d_cli.repairs import repair


def both_ways(triangles: np.ndarray, **options):
    """``repair`` as it runs, and with the topology's general path forced."""
    fast = repair(triangles, **options)
    with fast_path_refused():
        general = repair(triangles, **options)
    return fast, general


def same_repair(fast, general) -> None:
    (mesh, report), (want_mesh, want) = fast, general
    assert mesh.triangles.dtype == want_mesh.triangles.dtype
    assert mesh.triangles.tobytes() == want_mesh.triangles.tobytes()
    assert repr(report.to_dict()) == repr(want.to_dict())
    for got, expected in ((report.before, want.before), (report.after, want.after)):
        assert repr(dataclasses.asdict(got)) == repr(dataclasses.asdict(expected))


def holed_torus(u: int, v: int, every: int, seed: int, dtype=np.float64) -> np.ndarray:
    """The grid torus with every ``every``-th face gone, in a shuffled face order."""
    t = grid_torus(u, v).astype(dtype)
    kept = np.delete(t, np.arange(0, len(t), every), axis=0)
    return kept[np.random.default_rng(seed).permutation(len(kept))]


def took_fast_path(triangles: np.ndarray) -> bool:
    found = paired.paired_topology(_array_blocks(triangles), len(triangles), boundary=True)
    return found is not None and found.boundary.size > 0


def test_the_fast_layout_lists_the_general_paths_boundary_sides():
    t = holed_torus(30, 20, 7, seed=1)
    _, layout = topo.topology_and_layout(_array_blocks(t), len(t))
    with fast_path_refused():
        _, want = topo.topology_and_layout(_array_blocks(t), len(t))
    lone, groups = layout.edges, want.edges
    assert lone.nonmanifold.size == 0 and lone.misoriented.size == 0 and lone.forward is None
    np.testing.assert_array_equal(lone.side[lone.starts[lone.boundary]],
                                  np.sort(groups.side[groups.starts[groups.boundary]]))
    assert (lone.counts == 1).all() and lone.boundary.size == groups.boundary.size > 0
    # Asked for no edges, the same mesh's layout has none.
    assert topo.topology_and_layout(_array_blocks(t), len(t), edges=False)[1].edges is None


@pytest.mark.parametrize("every, seed, dtype", [(7, 1, np.float64), (3, 2, np.float32), (50, 3, np.float64)])
def test_holed_tori_repair_alike_both_ways(every, seed, dtype):
    t = holed_torus(40, 24, every, seed, dtype)
    assert took_fast_path(t)
    fast, general = both_ways(t)
    same_repair(fast, general)
    assert fast[1].step("holes").counts["holes_filled"] > 0


def test_the_numpy_road_repairs_alike_both_ways():
    # Without the compiled kernels the fast path's fans are numpy's union-find.
    t = holed_torus(20, 16, 5, seed=4)
    assert numpy_road(took_fast_path, t)
    same_repair(*numpy_road(both_ways, t))
    same_repair(numpy_road(repair, t), repair(t))


def test_holes_meeting_at_a_corner_repair_alike_both_ways():
    # Two faces sharing only a vertex removed: two holes touching at one point (a
    # non-manifold vertex), whose boundary walk passes that vertex twice.
    t = grid_torus(12, 10)
    a, b = 0, 1 * 10 + 1                    # the lower faces of cells (0, 0) and (1, 1): one corner shared
    shared = {tuple(p) for p in t[a].tolist()} & {tuple(p) for p in t[b].tolist()}
    assert len(shared) == 1
    holed = np.delete(t, [a, b], axis=0)
    assert took_fast_path(holed)
    fast, general = both_ways(holed)
    same_repair(fast, general)
    assert fast[1].before.nonmanifold_vertices == 1


def test_the_weld_step_and_the_cleanup_repair_alike_both_ways(cube):
    # An open cube beside a face and its reverse (a duplicate) and a zero-area face: the steps
    # that remove faces regroup the edges; the weld merges points by their ids.
    away = cube[5:6] + 3
    sliver = np.array([[[0, 0, 5], [0.5, 0, 5], [1, 0, 5]]], dtype=np.float64)
    t = np.concatenate([cube[2:], away, away[:, [0, 2, 1]], sliver])
    assert took_fast_path(t)
    for options in ({}, {"weld": 1e-6}):
        same_repair(*both_ways(t, **options))


def test_real_open_meshes_repair_alike_both_ways(real_meshes):
    taken = 0
    for mesh in real_surface_meshes(real_meshes, limit=60_000):
        t = mesh.triangles()
        if not took_fast_path(t):
            continue
        taken += 1
        same_repair(*both_ways(t))
    assert taken >= 1
