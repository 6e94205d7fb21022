"""X-ray layers (``Layer.xray``): lines inside a part are drawn in full colour, half as wide, where
other layers draw them dashed and half blended (so no pixel of a hidden line has their colour)."""

from __future__ import annotations

import dataclasses

import numpy as np
from helpers.meshes import cube_triangles

from p3d_cli.render.camera import make_camera
from p3d_cli.render.compose import compose
from p3d_cli.render.overlays import COLOURS, Layer, box_edges


def inside(picture, colour) -> np.ndarray:
    """Exact-colour pixels of the drawing area."""
    top, rows = picture.area
    return np.all(picture.pixels[top:top + rows] == colour, axis=-1)


def test_a_box_inside_a_cube_is_seen_only_as_xray():
    box = Layer("declared", "inside", segments=box_edges([0.3] * 3, [0.7] * 3), width=7)
    pictures = {xray: compose(cube_triangles(), make_camera("iso"), (800, 600),
                              [dataclasses.replace(box, xray=xray)], "cube", "iso")
                for xray in (False, True)}
    assert inside(pictures[False], COLOURS["declared"]).sum() == 0        # dashed, blended: no exact colour
    seen = inside(pictures[True], COLOURS["declared"])
    assert seen.sum() > 300
    # Half as wide as where nothing hides it: the same box, the same frame, no cube.
    bare = compose(np.zeros((0, 3, 3)), make_camera("iso"), (800, 600), [dataclasses.replace(box, xray=True)],
                   "cube", "iso", fit_points=cube_triangles().reshape(-1, 3))
    assert seen.sum() < 0.7 * inside(bare, COLOURS["declared"]).sum()
