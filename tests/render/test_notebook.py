"""Values show themselves in Jupyter: pictures of shapes and meshes, numbers and a thumbnail for results."""

from __future__ import annotations

import numpy as np

import p3d_cli as p3d
from p3d_cli.render.png import decode_png


def test_shapes_and_meshes_are_pictures(real_meshes):
    assert decode_png(p3d.parse_shape("cylinder:1,1,2")._repr_png_()).shape == (360, 480, 3)
    mesh = p3d.load_mesh(str(real_meshes / "trimesh__fuze.ply"))
    assert decode_png(mesh._repr_png_()).shape == (360, 480, 3)
    assert decode_png(p3d.picture("box")._repr_png_()).shape == (600, 800, 3)


def test_results_show_their_numbers_and_a_thumbnail(real_meshes):
    path = str(real_meshes / "trimesh__teapot.stl")
    check = p3d.check(path)._repr_html_()
    assert "FAILED" in check and "boundary edges" in check and ">64<" in check
    assert 'src="data:image/png;base64,' in check
    props = p3d.props("box:1,2,3")._repr_html_()
    assert "48" in props and "data:image/png" in props
    assert "(4, 4, 4)" in p3d.bounds("sphere:2")._repr_html_()
    # An array has no file to draw again: numbers alone, no error.
    triangle = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0]]], dtype=float)
    html = p3d.props(triangle)._repr_html_()
    assert "volume" in html and "<img" not in html
