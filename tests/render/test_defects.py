"""The defect overlay's edges and faces are check's: the same counts on made and real meshes."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.meshes import cube_triangles

import p3d_cli as p3d
from p3d_cli.render.defects import defect_geometry

CUBE = cube_triangles()


def flipped(t, i):
    t = t.copy()
    t[i] = t[i][::-1]
    return t


CASES = {
    "clean": CUBE,
    "open": CUBE[1:],
    "flipped face": flipped(CUBE, 3),
    "touching cubes": np.concatenate([CUBE, CUBE + [1.0, 0.0, 0.0]]),
    "fin": np.concatenate([CUBE, [[[0, 0, 0], [1, 0, 0], [0.5, -1, 0.5]]]]),
    "degenerate": np.concatenate([CUBE, [[[2, 2, 2], [2, 2, 2], [3, 2, 2]], [[4, 0, 0], [5, 0, 0], [6, 0, 0]]]]),
}


def assert_same_as_check(triangles):
    report = p3d.check(np.asarray(triangles, dtype=np.float64)).report
    found = defect_geometry(triangles)
    assert len(found.boundary) == report.boundary_edges
    assert len(found.nonmanifold) == report.nonmanifold_edges
    assert len(found.misoriented) == report.misoriented_edges
    assert len(found.degenerate) == report.degenerate_faces
    for sample in report.boundary_edge_samples:
        ends = {tuple(found.boundary[k, 0]) + tuple(found.boundary[k, 1]) for k in range(len(found.boundary))}
        a, b = sample.points
        assert tuple(a) + tuple(b) in ends or tuple(b) + tuple(a) in ends


@pytest.mark.parametrize("name", CASES)
def test_counts_match_check(name):
    assert_same_as_check(CASES[name])


@pytest.mark.parametrize("name", ["trimesh__bunny.ply", "trimesh__teapot.stl", "trimesh__soup.stl",
                                  "euclid__kitten.off"])
def test_counts_match_check_on_real_meshes(real_meshes, name):
    mesh = p3d.load_mesh(str(real_meshes / name))
    assert_same_as_check(mesh.triangles())


def test_degenerate_faces_are_marked_at_their_centroids():
    found = defect_geometry(CASES["degenerate"])
    assert found.degenerate.tolist() == [12, 13]
    assert np.allclose(found.degenerate_points, [[7 / 3, 2, 2], [5, 0, 0]])
