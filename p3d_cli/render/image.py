"""``Picture``: a rendered picture and what it shows (the value ``p3d_cli.picture`` returns)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Picture:
    """A rendered picture and what it shows.

    ``numpy.asarray(picture)`` is its ``pixels``; in a notebook it shows itself.

    Attributes
    ----------
    pixels : (h, w, 3) uint8
        The whole picture: title strip, drawing, legend strip.
    surface : (h, w, 3) uint8
        The shaded surface alone (no overlays, title or legend), for the SVG writer.
    strokes : tuple of draw.Stroke
        The overlays' lines and marks in pixels, for the SVG writer.
    layers : tuple of Layer
        The overlays drawn, in legend order.
    title : str
    note : str
        The view, at the top right.
    area : (int, int)
        First row and height of the drawing area.
    legend_top : int
        First row of the legend strip (the height when there is none).
    text_scale : int
    faces : int
        Triangles drawn.
    azimuth, elevation : float
        The camera's direction, degrees.
    camera : camera.Camera
    frame : camera.Frame
        Where world points land in the picture (``project``).
    """

    pixels: np.ndarray
    surface: np.ndarray
    strokes: tuple
    layers: tuple
    title: str
    note: str
    area: tuple[int, int]
    legend_top: int
    text_scale: int
    faces: int
    azimuth: float
    elevation: float
    camera: Any = None
    frame: Any = None

    def project(self, points) -> tuple[np.ndarray, np.ndarray]:
        """Pixel ``(x, y)`` in the whole picture (x right, y down) of world points ``(..., 3)``."""
        return self.frame.pixels(self.camera.view(np.asarray(points, dtype=np.float64)))

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        return int(self.pixels.shape[1]), int(self.pixels.shape[0])

    def __array__(self, dtype=None, copy=None):
        return self.pixels if dtype is None else self.pixels.astype(dtype)

    def to_png(self) -> bytes:
        """The picture as PNG bytes."""
        from p3d_cli.render.png import encode_png

        return encode_png(self.pixels, text={"Software": "p3d", "Title": self.title})

    def to_svg(self) -> str:
        """The picture as SVG text (see ``p3d_cli.render.svg``)."""
        from p3d_cli.render.svg import picture_svg

        return picture_svg(self)

    def _repr_png_(self) -> bytes:
        return self.to_png()
