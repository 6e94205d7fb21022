"""One picture from triangles, a camera and layers: fit, z-buffer, shade, overlays, title, legend."""

from __future__ import annotations

import numpy as np

from p3d_cli.render import legend
from p3d_cli.render.camera import Camera, Frame, fit_frame
from p3d_cli.render.draw import draw_layer, surface_depth
from p3d_cli.render.font import draw_text
from p3d_cli.render.image import Picture
from p3d_cli.render.raster import rasterize
from p3d_cli.render.shade import BACKGROUND, face_normals, shade, signed_volume_sign

#: Meshes up to this many faces are drawn at twice the size and averaged down (smooth edges);
#: beyond it faces are about a pixel each, and the time goes to them instead.
SUPERSAMPLE_FACES = 400_000
#: Colour of the small world-axes sign in the corner.
TRIAD = (95, 95, 105)


def compose(triangles: np.ndarray, camera: Camera, size: tuple[int, int], layers: list, title: str, note: str,
            fit_points: np.ndarray | None = None):
    """The ``Picture`` of ``triangles`` seen by ``camera`` with ``layers`` drawn over them.

    The frame fits the triangles and the layers, or ``fit_points`` ((k, 3) world points) when
    given: the frames of an animation share one."""
    width, height = size
    scale = legend.text_scale(width, height)
    rows = legend.layout(legend.legend_entries(layers), width, scale)
    title_height = legend.strip_height(1, scale)
    legend_height = legend.strip_height(len(rows), scale)
    area_height = max(height - title_height - legend_height, 32)
    legend_top = title_height + area_height

    triangles = np.asarray(triangles)
    dtype = np.float32 if triangles.dtype == np.float32 else np.float64
    # View coordinates about the middle of the part: float32 keeps its precision there.
    fitted = triangles if fit_points is None else np.asarray(fit_points, dtype=np.float64).reshape(-1, 1, 3)
    camera = camera.about(_middle(fitted, layers))
    view = camera.view(triangles.reshape(-1, 3).astype(dtype, copy=False)).reshape(-1, 3, 3)
    marks = _overlay_points(layers)
    fitted_view = view if fit_points is None else camera.view(fitted.reshape(-1, 3))
    low, high = _extent(fitted_view, camera.view(marks) if len(marks) else None)
    frame = fit_frame(low, high, width, area_height, top=title_height)

    ss = 2 if len(triangles) <= SUPERSAMPLE_FACES else 1
    big = Frame(frame.scale * ss, frame.center, width * ss, area_height * ss, 0)
    px, py = big.pixels(view)
    buffer = rasterize(px, py, view[..., 2], width * ss, area_height * ss)
    normals = face_normals(triangles) * signed_volume_sign(triangles) if len(triangles) else np.zeros((0, 3))
    view_normals = camera.about(np.zeros(3)).view(normals.astype(np.float64))
    view_normals[:, 2] *= -1                  # view() turns depth away from the camera; normals face it
    shaded = shade(buffer, view_normals, big.scale)
    depth, face = buffer.depth, buffer.face
    if ss > 1:
        # Average the ss x ss samples of each pixel (strided slices: numpy's reductions over
        # the axes of a reshaped array are many times slower here).
        total = np.zeros((area_height, width, 3), dtype=np.uint16)
        nearest = np.full((area_height, width), np.inf)
        for dy in range(ss):
            for dx in range(ss):
                total += shaded[dy::ss, dx::ss]
                np.minimum(nearest, depth[dy::ss, dx::ss], out=nearest)
        shaded = ((total + ss * ss // 2) // (ss * ss)).astype(np.uint8)
        depth = nearest
        face = face[::ss, ::ss]

    image = np.empty((height, width, 3), dtype=np.uint8)
    image[...] = BACKGROUND
    image[title_height:title_height + area_height] = shaded
    surface = image.copy()
    area = image[title_height:title_height + area_height]
    reach = surface_depth(depth)
    pixel_scale = min(width / 800, height / 600) ** 0.5
    strokes = []
    local = Frame(frame.scale, frame.center, width, area_height, 0)
    for layer in layers:
        for stroke in draw_layer(area, layer, camera, local, depth, reach, face, pixel_scale):
            strokes.append(_lifted(stroke, title_height))
    _triad(area, camera, scale)
    legend.draw_title(image, title, scale, note)
    if rows:
        legend.draw_legend(image, rows, legend_top, scale)
    return Picture(image, surface, tuple(strokes), tuple(layers), title, note, (title_height, area_height),
                   legend_top, scale, len(triangles), camera.azimuth, camera.elevation, camera, frame)


def _overlay_points(layers) -> np.ndarray:
    points = [layer.segments.reshape(-1, 3) for layer in layers if len(layer.segments)]
    points += [layer.points for layer in layers if len(layer.points)]
    return np.concatenate(points) if points else np.zeros((0, 3))


def _middle(triangles: np.ndarray, layers) -> np.ndarray:
    """The middle of the box of everything drawn (float64)."""
    if len(triangles):
        flat = triangles.reshape(-1, 3)
        low, high = flat.min(axis=0).astype(np.float64), flat.max(axis=0).astype(np.float64)
    else:
        marks = _overlay_points(layers)
        if not len(marks):
            return np.zeros(3)
        low, high = marks.min(axis=0), marks.max(axis=0)
    return 0.5 * (low + high)


def _extent(view: np.ndarray, marks: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Low and high view x, y of the faces and the overlays."""
    parts = []
    if len(view):
        flat = view.reshape(-1, 3)
        parts += [flat.min(axis=0).astype(np.float64), flat.max(axis=0).astype(np.float64)]
    if marks is not None and len(marks):
        parts += [marks.min(axis=0), marks.max(axis=0)]
    if not parts:
        return np.zeros(3), np.zeros(3)
    stack = np.array(parts)
    return stack.min(axis=0), stack.max(axis=0)


def _lifted(stroke, rows: int):
    """A stroke moved down by ``rows`` pixels (from the drawing area into the whole picture)."""
    from dataclasses import replace

    runs = stroke.runs.copy()
    runs[:, [1, 3]] += rows
    return replace(stroke, runs=runs)


def _triad(area: np.ndarray, camera: Camera, scale: int) -> None:
    """A small sign of the world axes x, y, z in the bottom-left corner of the drawing area."""
    h = area.shape[0]
    length = 14 * scale
    origin = np.array([10 * scale + length, h - 10 * scale - length], dtype=np.float64)
    for k, name in enumerate("xyz"):
        axis = np.zeros(3)
        axis[k] = 1.0
        v = camera.rotation @ axis
        if abs(v[0]) < 1e-9 and abs(v[1]) < 1e-9:
            draw_text(area, name, int(origin[0]) + 2, int(origin[1]) + 2, TRIAD, scale)   # along the view
            continue
        end = origin + length * np.array([v[0], -v[1]])
        t = np.linspace(0, 1, length + 1)
        cols = np.round(origin[0] + t * (end[0] - origin[0])).astype(int)
        rows = np.round(origin[1] + t * (end[1] - origin[1])).astype(int)
        keep = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < area.shape[1])
        area[rows[keep], cols[keep]] = TRIAD
        label = end + 5 * scale * np.array([v[0], -v[1]]) / max(np.hypot(v[0], v[1]), 1e-9)
        draw_text(area, name, int(label[0]) - 3 * scale, int(label[1]) - 4 * scale, TRIAD, scale)
