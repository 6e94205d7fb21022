"""Where the camera looks from: named views, azimuth and elevation, and the orthographic fit.

Conventions (docs/render.md): the world's up axis is +z unless ``up`` says otherwise. The
camera looks at the part from the direction

    d = (sin(az) cos(el), -cos(az) cos(el), sin(el))

(from the part towards the camera), so azimuth 0 is the front (camera on -y, looking along
+y, x to the right), 90 the right side (camera on +x), 180 the back, -90 the left; elevation 90
is the top (x right, y up) and -90 the bottom (x right, y down). Screen right is
``r = (cos(az), sin(az), 0)`` and screen up ``u = d × r``: the front and back views are mirror
images left to right, exactly (the standard views' sines and cosines are exact).

The projection is orthographic (parallel): sizes do not shrink with distance, so a picture
can be measured like a drawing, and what is in front is decided by depth alone.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import UsageError

#: Named views: (azimuth, elevation) in degrees. ``iso`` is the true isometric direction
#: (1, -1, 1): elevation atan(1/√2) = 35.264°.
VIEWS = {
    "iso": (45.0, math.degrees(math.atan(1 / math.sqrt(2)))),
    "front": (0.0, 0.0),
    "back": (180.0, 0.0),
    "left": (-90.0, 0.0),
    "right": (90.0, 0.0),
    "top": (0.0, 90.0),
    "bottom": (0.0, -90.0),
}

#: Rotations taking each choice of the part's up axis to +z (rows: the new x, y, z).
UP_AXES = {
    "z": np.eye(3),
    "y": np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]]),   # y -> z, z -> -y
    "x": np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]),    # x -> z, y -> x
}


def _exact_trig(degrees: float) -> tuple[float, float]:
    """``(cos, sin)`` of an angle, exact at multiples of 90° (so the standard views mirror exactly)."""
    quarter = degrees / 90.0
    if quarter == round(quarter):
        return [(1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0)][int(round(quarter)) % 4]
    radians = math.radians(degrees)
    return math.cos(radians), math.sin(radians)


@dataclass(frozen=True)
class Camera:
    """An orthographic camera: the world-to-view rotation, the scale and the picture's centre.

    Attributes
    ----------
    rotation : (3, 3) float64
        Rows: screen right, screen up, and the direction towards the camera, in world
        coordinates (after the up-axis turn).
    azimuth, elevation : float
        Degrees.
    origin : (3,) float64 or None
        The world point at view ``(0, 0, 0)`` (default the world origin).
    """

    rotation: np.ndarray
    azimuth: float
    elevation: float
    origin: np.ndarray | None = None

    def view(self, points: np.ndarray) -> np.ndarray:
        """``(..., 3)`` world points as view coordinates: right, up, and depth (smaller is nearer).
        float32 points stay float32 (less memory and time for large meshes)."""
        points = np.asarray(points)
        dtype = np.float32 if points.dtype == np.float32 else np.float64
        if self.origin is not None:
            points = points - self.origin.astype(dtype)
        out = points.astype(dtype, copy=False) @ self.rotation.T.astype(dtype)
        out[..., 2] *= -1
        return out

    def about(self, origin) -> "Camera":
        """The same camera with view ``(0, 0, 0)`` at ``origin``."""
        from dataclasses import replace

        return replace(self, origin=np.asarray(origin, dtype=np.float64))

    @property
    def towards_camera(self) -> np.ndarray:
        """(3,) world direction from the part towards the camera."""
        return self.rotation[2]


def make_camera(view: str | None = "iso", azimuth: float | None = None, elevation: float | None = None,
                up: str = "z") -> Camera:
    """The camera of a named view, or of an azimuth and elevation (either overrides the view's).

    Raises
    ------
    UsageError
        An unknown view or up axis, or an elevation outside [-90, 90].
    """
    if view is not None and view not in VIEWS:
        raise UsageError("view", f"no view named {view!r}", "views are: " + ", ".join(VIEWS))
    if up not in UP_AXES:
        raise UsageError("up", f"{up!r} is not an axis", "use x, y or z")
    az, el = VIEWS[view or "iso"]
    az = az if azimuth is None else float(azimuth)
    el = el if elevation is None else float(elevation)
    if not (math.isfinite(az) and math.isfinite(el)) or not -90.0 <= el <= 90.0:
        raise UsageError("elevation" if math.isfinite(az) else "azimuth",
                         f"({az}, {el}) is not a direction", "give an azimuth in degrees and an elevation in [-90, 90]")
    ca, sa = _exact_trig(az)
    ce, se = _exact_trig(el)
    towards = np.array([sa * ce, -ca * ce, se])
    right = np.array([ca, sa, 0.0])
    upward = np.cross(towards, right)
    rotation = np.stack([right, upward, towards]) @ UP_AXES[up]
    return Camera(rotation, az, el)


@dataclass(frozen=True)
class Frame:
    """Where view coordinates land in the picture: ``px = (x - cx) s + w / 2`` (pixels right)
    and ``py = top + h / 2 - (y - cy) s`` (pixels down).

    Attributes
    ----------
    scale : float
        Pixels per unit length.
    center : (2,) float64
        The view point at the middle of the drawing area.
    width, height : int
        The drawing area's size in pixels.
    top : int
        Its first row in the picture (a title strip may sit above it).
    """

    scale: float
    center: np.ndarray
    width: int
    height: int
    top: int = 0

    def pixels(self, view_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Pixel ``(x, y)`` of view coordinates ``(..., 3)``."""
        px = (view_points[..., 0] - self.center[0]) * self.scale + self.width / 2
        py = (self.top + self.height / 2) - (view_points[..., 1] - self.center[1]) * self.scale
        return px, py


def fit_frame(low: np.ndarray, high: np.ndarray, width: int, height: int, top: int = 0,
              margin: float = 0.06) -> Frame:
    """The frame that shows the view-space box ``[low, high]`` (x and y) whole, centred, with
    ``margin`` of the area free on each side."""
    span = np.maximum(np.asarray(high[:2], dtype=np.float64) - np.asarray(low[:2], dtype=np.float64), 0.0)
    room = np.array([width, height], dtype=np.float64) * (1 - 2 * margin)
    with np.errstate(divide="ignore"):
        ratios = np.where(span > 0, room / np.where(span > 0, span, 1.0), np.inf)
    scale = float(ratios.min())
    if not math.isfinite(scale):
        scale = 1.0               # a single point: any scale shows it
    center = 0.5 * (np.asarray(low[:2], dtype=np.float64) + np.asarray(high[:2], dtype=np.float64))
    return Frame(scale, center, width, height, top)
