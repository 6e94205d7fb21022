"""The z-buffer against brute force: at every pixel centre, the nearest face that contains it."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.render.raster import rasterize


def brute_force(x, y, z, width, height):
    """Per pixel centre, the depth of the nearest triangle containing it (closed triangles)."""
    depth = np.full((height, width), np.inf)
    jj, ii = np.mgrid[0:height, 0:width]
    px, py = ii + 0.5, jj + 0.5
    for k in range(len(x)):
        (x0, x1, x2), (y0, y1, y2), (z0, z1, z2) = x[k], y[k], z[k]
        area = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0)
        if area == 0:
            continue
        w1 = ((px - x0) * (y2 - y0) - (py - y0) * (x2 - x0)) / area
        w2 = ((py - y0) * (x1 - x0) - (px - x0) * (y1 - y0)) / area
        w0 = 1 - w1 - w2
        inside = (w0 >= 0) & (w1 >= 0) & (w2 >= 0)
        d = w0 * z0 + w1 * z1 + w2 * z2
        depth = np.where(inside & (d < depth), d, depth)
    return depth


def test_the_nearer_of_two_crossing_triangles_wins_on_each_side():
    # Two triangles that cross along x = 10: each is in front on one side (no order of faces,
    # as the painter's algorithm needs, gets this right).
    x = np.array([[0.0, 20.0, 0.0], [0.0, 20.0, 20.0]])
    y = np.array([[0.0, 0.0, 20.0], [0.0, 0.0, 20.0]])
    z = np.array([[0.0, 2.0, 0.0], [2.0, 0.0, 0.0]])
    buffer = rasterize(x, y, z, 20, 20)
    assert buffer.face[1, 2] == 0 and buffer.face[1, 17] == 1
    assert np.allclose(buffer.depth, brute_force(x, y, z, 20, 20), atol=1e-6)


@given(st.integers(1, 40), st.integers(0, 2**32 - 1))
def test_depth_matches_brute_force(count, seed):
    rng = np.random.default_rng(seed)
    width, height = 37, 29
    x = rng.uniform(-10, width + 10, size=(count, 3))
    y = rng.uniform(-10, height + 10, size=(count, 3))
    z = rng.uniform(0, 5, size=(count, 3))
    expected = brute_force(x, y, z, width, height)
    buffer = rasterize(x, y, z, width, height)
    found = np.isfinite(buffer.depth)
    # Coverage agrees except at centres within rounding of an edge; depth to the quantisation.
    assert (found != np.isfinite(expected)).sum() <= 2
    both = found & np.isfinite(expected)
    assert np.allclose(buffer.depth[both], expected[both], atol=1e-5 * 5 + 1e-6)
    faces = buffer.face[found]
    assert faces.min() >= 0 and faces.max() < count


def test_huge_triangles_are_done_in_chunks(monkeypatch):
    from p3d_cli.render import raster

    monkeypatch.setattr(raster, "CHUNK", 1000)
    x = np.array([[0.0, 400.0, 0.0]])
    y = np.array([[0.0, 0.0, 300.0]])
    z = np.zeros((1, 3))
    buffer = raster.rasterize(x, y, z, 400, 300)
    # Pixel centres strictly inside the triangle x/400 + y/300 <= 1.
    jj, ii = np.mgrid[0:300, 0:400]
    inside = (ii + 0.5) / 400 + (jj + 0.5) / 300 <= 1
    assert np.array_equal(buffer.covered, inside)


def test_nothing_to_draw():
    empty = np.zeros((0, 3))
    buffer = rasterize(empty, empty, empty, 8, 6)
    assert buffer.face.shape == (6, 8) and not buffer.covered.any()
    # A zero-area face and a face off the picture cover nothing.
    x = np.array([[0.0, 1.0, 2.0], [-9.0, -8.0, -9.0]])
    y = np.array([[0.0, 1.0, 2.0], [0.0, 0.0, 5.0]])
    assert not rasterize(x, y, np.zeros((2, 3)), 8, 6).covered.any()
