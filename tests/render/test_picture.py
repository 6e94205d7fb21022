"""Pictures read back: colours where the overlays project, mirrored views, axes along edges, sizes."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.meshes import cube_triangles

import p3d_cli as p3d
from p3d_cli.render.overlays import COLOURS, equivalent_half_extents
from p3d_cli.render.picture import picture as render
from p3d_cli.render.png import decode_png

CUBE = cube_triangles()
BOTTOMLESS = CUBE[2:]            # faces 0 and 1 are the square at z = 0


def drawing(picture) -> np.ndarray:
    """The drawing area (between the title and the legend) of the finished picture."""
    top, rows = picture.area
    return picture.pixels[top:top + rows]


def pixels_of(picture, colour) -> np.ndarray:
    """(k, 2) x, y (whole-picture pixel centres) of the drawing's pixels of exactly ``colour``."""
    top, _ = picture.area
    rows, cols = np.nonzero(np.all(drawing(picture) == colour, axis=-1))
    return np.stack([cols + 0.5, rows + top + 0.5], axis=1)


def distance_to_segments(points, a, b) -> np.ndarray:
    """Distance of each point (k, 2) to the nearest of the segments a[i]-b[i] (m, 2)."""
    d = b - a
    t = np.clip(((points[:, None, :] - a[None]) * d[None]).sum(-1) / np.maximum((d * d).sum(-1), 1e-12), 0, 1)
    nearest = a[None] + t[..., None] * d[None]
    return np.sqrt(((points[:, None, :] - nearest) ** 2).sum(-1)).min(axis=1)


def projected(picture, segments):
    x, y = picture.project(np.asarray(segments, dtype=np.float64))
    return np.stack([x[:, 0], y[:, 0]], axis=1), np.stack([x[:, 1], y[:, 1]], axis=1)


def test_the_hole_of_a_bottomless_cube_is_outlined_in_the_boundary_colour_and_nothing_else_is():
    picture = render(BOTTOMLESS, view="bottom", show="defects")
    red = pixels_of(picture, COLOURS["boundary"])
    border = CUBE[:2].reshape(-1, 3)
    edges = np.array([[[0, 0, 0], [1, 0, 0]], [[1, 0, 0], [1, 1, 0]], [[1, 1, 0], [0, 1, 0]], [[0, 1, 0], [0, 0, 0]]])
    assert border.min() == 0 and border[:, 2].max() == 0
    a, b = projected(picture, edges)
    assert len(red) > 100
    assert distance_to_segments(red, a, b).max() <= 2.0               # only on the border
    for t in np.linspace(0, 1, 41):                                       # and all along it
        for p in a + t * (b - a):
            assert np.hypot(*(red - p).T).min() <= 2.0
    assert [layer.label for layer in picture.layers] == ["4 boundary edges"]


def test_a_clean_cube_shows_no_defect_colour():
    picture = render(CUBE, view="iso", show="defects")
    assert picture.layers == ()
    for key in ("boundary", "nonmanifold", "misoriented", "degenerate", "intersecting"):
        assert len(pixels_of(picture, COLOURS[key])) == 0


def test_a_defect_behind_the_part_is_drawn_hidden_not_in_the_defect_colour():
    # Seen from above, the far edges of the hole in the bottom are behind the cube.
    picture = render(BOTTOMLESS, view="iso", show="defects")
    red = pixels_of(picture, COLOURS["boundary"])
    hidden = [s for s in picture.strokes if s.key == "boundary" and not s.visible]
    seen = [s for s in picture.strokes if s.key == "boundary" and s.visible]
    assert hidden and seen and len(red) > 100
    for run in np.concatenate([s.runs for s in hidden]):
        a, b = run[:2], run[2:]
        length = np.hypot(*(b - a))
        for t in np.linspace(6 / length, 1 - 6 / length, 20) if length > 12 else ():
            p = a + t * (b - a)
            assert np.hypot(*(red - p).T).min() > 2.0


@pytest.mark.parametrize("thing", ["corner:2,1,1", "corner:1,0.5,3"])
def test_front_and_back_views_are_mirror_images(thing):
    front = render(thing, view="front", size=(400, 300))
    back = render(thing, view="back", size=(400, 300))
    covered_front = np.any(drawing_surface(front) != 255, axis=-1)
    covered_back = np.any(drawing_surface(back) != 255, axis=-1)
    assert covered_front.sum() > 5000
    assert not np.array_equal(covered_front, covered_front[:, ::-1])       # not symmetric itself
    assert (covered_front != covered_back[:, ::-1]).mean() < 1e-3


def drawing_surface(picture) -> np.ndarray:
    top, rows = picture.area
    return picture.surface[top:top + rows]


def test_front_and_back_of_a_real_mesh_are_mirror_images(real_meshes):
    path = real_meshes / "trimesh__fuze.ply"
    front = render(path, view="front", size=(320, 240))
    back = render(path, view="back", size=(320, 240))
    a = np.any(drawing_surface(front) != 255, axis=-1)
    b = np.any(drawing_surface(back) != 255, axis=-1)[:, ::-1]
    assert a.sum() > 2000 and (a != b).mean() < 2e-3


def test_principal_axes_of_a_turned_box_point_along_its_edges():
    turn = p3d.rotation_from_axis_degrees("z", 30)
    placement = p3d.Placement(rotation=turn, translation=[5.0, -2.0, 1.0])
    picture = render("box:1,2,3", view="top", show="axes", placement=placement)
    axes = {layer.key: layer for layer in picture.layers}
    assert set(axes) == {"axis1", "axis2", "axis3"}
    # Box 2 x 4 x 6: the smallest moment is about the longest side (z), the largest about x.
    edges = {"axis1": turn[:, 2], "axis2": turn[:, 1], "axis3": turn[:, 0]}
    for key, edge in edges.items():
        stroke = axes[key].segments[0]
        direction = (stroke[1] - stroke[0]) / np.linalg.norm(stroke[1] - stroke[0])
        assert abs(abs(direction @ edge) - 1) < 1e-12
        assert np.allclose(stroke.mean(axis=0), [5.0, -2.0, 1.0])
    # In the picture (seen from the top), axis 3's colour lies along the turned x edge.
    green = pixels_of(picture, COLOURS["axis3"])
    a, b = projected(picture, axes["axis3"].segments[:1])
    assert len(green) > 50
    assert np.median(distance_to_segments(green, a, b)) <= 1.0


def test_the_equivalent_box_of_a_box_is_the_box_itself():
    result = p3d.props("box:1,2,3")
    assert np.allclose(sorted(equivalent_half_extents(result.properties)), [1, 2, 3], rtol=1e-12)
    ellipsoid = p3d.props("ellipsoid:1,2,3")
    assert np.allclose(sorted(equivalent_half_extents(ellipsoid.properties, "ellipsoid")), [1, 2, 3],
                       rtol=1e-12)


def test_the_bounds_overlay_is_the_box_of_the_part():
    picture = render("sphere:2", view="front", show="bounds")
    (layer,) = picture.layers
    corners = layer.segments.reshape(-1, 3)
    assert np.allclose(corners.min(axis=0), -2) and np.allclose(corners.max(axis=0), 2)
    assert layer.label == "bounds 4 x 4 x 4"


@pytest.mark.parametrize("size", [(800, 600), (320, 240), (1024, 200)])
def test_the_picture_has_the_size_asked_for(size):
    picture = render("cylinder", size=size, show="axes,bounds")
    assert picture.pixels.shape == (size[1], size[0], 3)
    assert decode_png(picture.to_png()).shape == (size[1], size[0], 3)
    assert np.asarray(picture).shape == (size[1], size[0], 3)


def test_bad_parameters_are_refused():
    with pytest.raises(p3d.UsageError, match="show"):
        render("box", show="everything")
    with pytest.raises(p3d.UsageError, match="size"):
        render("box", size=(10, 10))
    with pytest.raises(p3d.UsageError, match="view"):
        render("box", view="sideways")
    with pytest.raises(p3d.UsageError, match="defects"):
        render("box", show="defects")


def test_svg_holds_the_surface_as_png_and_the_overlays_as_vectors():
    import base64
    import xml.etree.ElementTree as ET

    picture = render(BOTTOMLESS, view="bottom", show="defects,bounds", size=(400, 300))
    svg = picture.to_svg()
    root = ET.fromstring(svg)
    ns = {"svg": "http://www.w3.org/2000/svg"}
    (image,) = root.findall("svg:image", ns)
    href = image.get("href")
    assert href.startswith("data:image/png;base64,")
    surface = decode_png(base64.b64decode(href.split(",", 1)[1]))
    assert surface.shape == (picture.area[1], 400, 3)
    paths = root.findall("svg:path", ns)
    assert any(p.get("class") == "boundary" for p in paths)
    assert "http://" not in svg.replace('xmlns="http://www.w3.org/2000/svg"', "")
    texts = " ".join(t.text for t in root.iter("{http://www.w3.org/2000/svg}text"))
    assert "4 boundary edges" in texts
