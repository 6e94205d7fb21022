"""Drawing overlay layers into a shaded picture, each mark tested against the depth buffer.

A line is sampled about once per pixel along its length; a sample is visible when it is no
deeper than the surface at some pixel of its 3 x 3 neighbourhood (plus a little slack): lines
that lie on the surface (a hole's border) are seen where the surface is, and a line behind a
wall is not. Visible samples are drawn in the layer's colour at full strength, ``width`` pixels
wide; hidden ones thin, dashed and half blended into what is in front, so that a defect on the
far side is still found but not mistaken for one in front. Marks (points) are squares with a
dark rim; tinted faces are blended where they are the visible face.

The same samples give ``Stroke`` runs (a stretch of one line that is all visible or all
hidden) for the SVG writer, which draws them as vector lines over the raster surface.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.render.camera import Camera, Frame
from p3d_cli.render.font import CELL_HEIGHT, draw_text
from p3d_cli.render.shade import neighbours

#: Samples of one line per pixel of its length.
DENSITY = 1.0
#: Rings around the places a layer marks: at most this many, each this far across (pixels at
#: 800 x 600), in this colour (no layer's).
RINGS = 12
RING_CELL = 40
RING_COLOUR = (60, 60, 70)
#: Hidden lines: dash and gap lengths in samples, and how much of the colour shows.
DASH = 4
HIDDEN_ALPHA = 0.5


@dataclass(frozen=True)
class Stroke:
    """Straight runs of one layer, in pixels: ``(k, 4)`` rows ``x0, y0, x1, y1``; marks are runs
    of zero length, ``width`` wide; a tag is one point with its ``text``."""

    key: str
    colour: tuple[int, int, int]
    visible: bool
    runs: np.ndarray
    width: float
    text: str = ""


def surface_depth(depth: np.ndarray) -> np.ndarray:
    """The deepest surface depth over each pixel's 3 x 3 neighbourhood (``inf`` next to empty
    pixels): a line sample no deeper than this is visible."""
    h, w = depth.shape
    out = depth.copy()
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        here, there = neighbours(h, w, dy, dx)
        np.maximum(out[here], depth[there], out=out[here])
        np.maximum(out[there], depth[here], out=out[there])
    return out


def line_samples(points: np.ndarray, camera: Camera, frame: Frame):
    """Pixel positions, depths and segment numbers of samples along world segments ``(k, 2, 3)``."""
    view = camera.view(np.asarray(points, dtype=np.float64))
    px, py = frame.pixels(view)
    length = np.hypot(px[:, 1] - px[:, 0], py[:, 1] - py[:, 0])
    count = np.maximum(np.ceil(length * DENSITY).astype(np.int64), 1) + 1
    segment = np.repeat(np.arange(len(points)), count)
    first = np.r_[0, np.cumsum(count)[:-1]]
    step = np.arange(segment.size) - np.repeat(first, count)
    t = step / np.repeat(count - 1, count)
    x = px[segment, 0] + t * (px[segment, 1] - px[segment, 0])
    y = py[segment, 0] + t * (py[segment, 1] - py[segment, 0])
    z = view[segment, 0, 2] + t * (view[segment, 1, 2] - view[segment, 0, 2])
    return x, y, z, segment, step


def visible_samples(x, y, z, reach: np.ndarray, slack: float) -> np.ndarray:
    """Which samples are in front of (or on) the surface; samples off the picture count as hidden."""
    h, w = reach.shape
    col, row = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    inside = (col >= 0) & (col < w) & (row >= 0) & (row < h)
    out = np.zeros(x.shape, dtype=bool)
    out[inside] = z[inside] <= reach[row[inside], col[inside]] + slack
    return out


def runs(x, y, segment, visible) -> tuple[np.ndarray, np.ndarray]:
    """Straight runs of equal visibility: ``(k, 4)`` pixel rows and their visibility."""
    if x.size == 0:
        return np.zeros((0, 4)), np.zeros(0, dtype=bool)
    start = np.r_[True, (segment[1:] != segment[:-1]) | (visible[1:] != visible[:-1])]
    first = np.flatnonzero(start)
    last = np.r_[first[1:] - 1, x.size - 1]
    rows = np.stack([x[first], y[first], x[last], y[last]], axis=1)
    return rows, visible[first]


def stamp(image: np.ndarray, x, y, colour, width: float, alpha: float = 1.0) -> None:
    """Square brush of ``width`` pixels centred on each ``(x, y)``, blended by ``alpha``."""
    h, w = image.shape[:2]
    radius = max(width, 1.0) / 2
    offsets = np.arange(int(np.ceil(-radius + 0.5)), int(np.floor(radius - 0.5)) + 1)
    if offsets.size == 0:
        offsets = np.array([0])
    base_c, base_r = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    cols = (base_c[:, None, None] + offsets[None, None, :]).repeat(offsets.size, axis=1).reshape(-1)
    rows = (base_r[:, None, None] + offsets[None, :, None]).repeat(offsets.size, axis=2).reshape(-1)
    keep = (cols >= 0) & (cols < w) & (rows >= 0) & (rows < h)
    rows, cols = rows[keep], cols[keep]
    colour = np.asarray(colour, dtype=np.float32)
    if alpha >= 1.0:
        image[rows, cols] = colour.astype(np.uint8)
    else:
        pixel = np.unique(rows * w + cols)
        r, c = pixel // w, pixel % w
        image[r, c] = (image[r, c].astype(np.float32) * (1 - alpha) + colour * alpha + 0.5).astype(np.uint8)


def draw_layer(image: np.ndarray, layer, camera: Camera, frame: Frame, depth: np.ndarray, reach: np.ndarray,
               face: np.ndarray, pixel_scale: float) -> list[Stroke]:
    """Draw one layer into ``image`` ((h, w, 3) uint8) and return its strokes (for SVG).

    ``depth`` and ``face`` are the surface's depth and face buffers at the picture's size,
    ``reach`` ``surface_depth(depth)``; ``pixel_scale`` scales line widths and marks with the
    picture (1 at 800 x 600)."""
    strokes = []
    colour = layer.colour
    width = max(1.0, round(layer.width * pixel_scale))
    if len(layer.faces):
        tint = np.isin(face, layer.faces)
        blend = image[tint].astype(np.float32) * 0.35 + np.array(colour, np.float32) * 0.65
        image[tint] = (blend + 0.5).astype(np.uint8)
    slack = 1.5 / frame.scale
    if len(layer.segments):
        x, y, z, segment, step = line_samples(layer.segments, camera, frame)
        seen = visible_samples(x, y, z, reach, slack)
        hidden_width = max(1.0, round(width / 2)) if layer.xray else 1.0
        if layer.xray:
            stamp(image, x[~seen], y[~seen], colour, hidden_width)
        else:
            dashed = ~seen & ((step // DASH) % 2 == 0)
            stamp(image, x[dashed], y[dashed], colour, 1.0, HIDDEN_ALPHA)
        stamp(image, x[seen], y[seen], colour, width)
        rows, flags = runs(x, y, segment, seen)
        for flag in (False, True):
            if (flags == flag).any():
                strokes.append(Stroke(layer.key, colour, flag, rows[flags == flag], width if flag else hidden_width))
    if len(layer.points):
        view = camera.view(np.asarray(layer.points, dtype=np.float64))
        px, py = frame.pixels(view)
        seen = visible_samples(px, py, view[:, 2], reach, slack)
        size = max(5.0, round(7 * pixel_scale))
        stamp(image, px[~seen], py[~seen], colour, size, HIDDEN_ALPHA)
        stamp(image, px[seen], py[seen], (40, 40, 40), size + 2)
        stamp(image, px[seen], py[seen], colour, size)
        for flag in (False, True):
            if (seen == flag).any():
                marks = np.stack([px[seen == flag], py[seen == flag]] * 2, axis=1)
                strokes.append(Stroke(layer.key, colour, bool(flag), marks, size))
    if layer.ring:
        strokes += _rings(image, layer, camera, frame, pixel_scale)
    for text, point in layer.tags:
        view = camera.view(np.asarray(point, dtype=np.float64)[None])
        px, py = frame.pixels(view)
        scale = max(1, int(round(pixel_scale * 2)))
        left, top = int(px[0]) + 2, int(py[0]) - CELL_HEIGHT * scale // 2
        draw_text(image, text, left, top, colour, scale)
        strokes.append(Stroke(layer.key, colour, True, np.array([[left, top, left, top]], dtype=np.float64),
                              CELL_HEIGHT * scale, text))
    return strokes


def _rings(image: np.ndarray, layer, camera: Camera, frame: Frame, pixel_scale: float) -> list[Stroke]:
    """Circle the few places a layer marks (segment middles, points, tinted faces are left out)."""
    places = [layer.segments.mean(axis=1)] if len(layer.segments) else []
    places += [layer.points] if len(layer.points) else []
    if not places:
        return []
    px, py = frame.pixels(camera.view(np.concatenate(places)))
    cell = RING_CELL * pixel_scale
    keys = np.unique(np.stack([np.floor(px / cell), np.floor(py / cell)], axis=1), axis=0)
    if len(keys) > RINGS:
        return []
    radius = 0.5 * cell
    strokes = []
    for kx, ky in keys:
        near = (np.floor(px / cell) == kx) & (np.floor(py / cell) == ky)
        cx, cy = float(px[near].mean()), float(py[near].mean())
        t = np.linspace(0, 2 * np.pi, 8 * int(radius) + 16)
        ring_x, ring_y = cx + radius * np.cos(t), cy + radius * np.sin(t)
        stamp(image, ring_x, ring_y, RING_COLOUR, max(2.0, round(2 * pixel_scale)))
        runs = np.stack([ring_x[:-1], ring_y[:-1], ring_x[1:], ring_y[1:]], axis=1)
        strokes.append(Stroke("ring", RING_COLOUR, True, runs, max(1.0, round(1.5 * pixel_scale))))
    return strokes
