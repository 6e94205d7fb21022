"""What can be drawn over a part (``show=``), each as a ``Layer`` of 3-D lines, marks and faces.

Every overlay has its own colour, used for nothing else in a picture (the tests look for it):

- ``defects``: boundary edges (red), non-manifold edges (magenta), misoriented edges (orange),
  degenerate faces (marked, yellow) and self-intersecting faces (cyan, tinted) when ``p3d
  check`` reports them;
- ``axes``: the principal frame at the centre of mass: each axis drawn through the centre, its
  half-length ``L · I_k / I_max`` (``L`` half the largest bounding-box side), numbered 1, 2, 3 in
  ascending order of moment;
- ``inertia``: the equivalent uniform box, the box of the same mass and principal moments,
  placed on the principal frame (half-extents ``a_k² = 3 (I_i + I_j - I_k) / (2 m)``);
  ``ellipsoid`` the equivalent ellipsoid (``a_k² = 5 (I_i + I_j - I_k) / (2 m)``);
- ``bounds``: the axis-aligned bounding box.

``declared`` is the colour of a robot link's declared inertia, drawn beside the one its
geometry gives (``inertia``) in ``p3d robot check --report`` (``p3d_cli.render.robot_page``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The overlays ``show=`` accepts, in drawing order.
SHOW = ("defects", "axes", "inertia", "ellipsoid", "bounds")

#: One colour per kind of mark (RGB 0-255); no two alike, none a shade of the surface.
COLOURS = {
    "boundary": (230, 0, 35),
    "nonmanifold": (200, 0, 200),
    "misoriented": (255, 140, 0),
    "degenerate": (240, 210, 0),
    "intersecting": (0, 185, 215),
    "axis1": (0, 150, 60),
    "axis2": (20, 80, 230),
    "axis3": (120, 60, 20),
    "inertia": (0, 120, 120),
    "ellipsoid": (110, 40, 160),
    "bounds": (90, 90, 110),
    "joint": (200, 90, 0),
    "declared": (215, 35, 115),
}


@dataclass(frozen=True)
class Layer:
    """One entry of the legend and what it draws.

    Attributes
    ----------
    key : str
        A key of ``COLOURS``.
    label : str
        The legend's text.
    segments : (k, 2, 3) float64
        Lines, world coordinates.
    points : (m, 3) float64
        Marks (for what covers no pixel, such as a zero-area face).
    faces : (f,) int64
        Faces to tint.
    tags : tuple of (str, (3,) float)
        Text drawn beside a world point (the axes' numbers).
    width : int
        Line width in pixels at 800 x 600.
    ring : bool
        Circle each place where the layer draws (in a neutral colour) when there are few: a
        single short defect edge on a large part is then found at a glance.
    xray : bool
        Draw the lines behind the surface in full colour too (half as wide, not dashed): for
        what lies mostly inside a part, such as the inertia boxes of a robot link (PNG; the
        SVG writer draws them dashed, as other hidden lines).
    """

    key: str
    label: str
    segments: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3)))
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    faces: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    tags: tuple = ()
    width: int = 2
    ring: bool = False
    xray: bool = False

    @property
    def colour(self) -> tuple[int, int, int]:
        return COLOURS[self.key]


def number(x: float) -> str:
    """A number in four significant digits for a legend."""
    return f"{float(x) + 0.0:.4g}"


def plural(n: int, noun: str) -> str:
    return f"{n:,} {noun}{'' if n == 1 else 's'}"


def defect_layers(defects, intersecting: np.ndarray | None = None, intersections: int | None = None) -> list[Layer]:
    """The defect layers that have something to draw (``defects``: a ``DefectGeometry``)."""
    out = []
    for key, noun in (("boundary", "boundary edge"), ("nonmanifold", "non-manifold edge"),
                      ("misoriented", "misoriented edge")):
        segments = getattr(defects, key)
        if len(segments):
            out.append(Layer(key, plural(len(segments), noun), segments=segments, ring=True))
    if len(defects.degenerate):
        out.append(Layer("degenerate", plural(len(defects.degenerate), "degenerate face"),
                         points=defects.degenerate_points, ring=True))
    if intersecting is not None and intersecting.size:
        count = intersections if intersections is not None else intersecting.size
        out.append(Layer("intersecting", plural(count, "self-intersection"), faces=intersecting, ring=True))
    return out


def axes_layer(properties, size: float) -> Layer | None:
    """The principal frame of ``properties`` (a ``MassProperties``), or None without one.

    ``size`` is the largest side of the bounding box: the axis of the largest moment reaches
    half of it on each side of the centre."""
    if properties.principal_axes is None or properties.center_of_mass is None:
        return None
    moments = np.abs(np.asarray(properties.principal_moments, dtype=np.float64))
    top = float(moments.max()) or 1.0
    centre = np.asarray(properties.center_of_mass, dtype=np.float64)
    segments, tags = [], []
    for k in range(3):
        half = 0.5 * size * max(moments[k] / top, 0.08)      # never too short to see
        axis = np.asarray(properties.principal_axes[k], dtype=np.float64)
        tip = centre + half * axis
        segments.append([centre - half * axis, tip])
        # An arrowhead: two short strokes back from the tip, in the plane of the next axis.
        other = np.asarray(properties.principal_axes[(k + 1) % 3], dtype=np.float64)
        back = tip - 0.12 * half * axis
        segments += [[tip, back + 0.06 * half * other], [tip, back - 0.06 * half * other]]
        tags.append((str(k + 1), tip + 0.04 * half * axis))
    values = ", ".join(number(m) for m in properties.principal_moments)
    label = f"principal axes 1-2-3 at the centre of mass (I = {values}; length ~ I)"
    return Layer("axis1", label, segments=np.array(segments), tags=tuple(tags))


def axis_layers(properties, size: float) -> list[Layer]:
    """``axes_layer`` split into one layer per axis (one colour each)."""
    whole = axes_layer(properties, size)
    if whole is None:
        return []
    moments = properties.principal_moments
    out = []
    for k in range(3):
        label = f"axis {k + 1}: I{k + 1} = {number(moments[k])}"
        out.append(Layer(f"axis{k + 1}", label, segments=whole.segments[3 * k:3 * k + 3], tags=(whole.tags[k],)))
    return out


def equivalent_half_extents(properties, shape: str = "box") -> np.ndarray | None:
    """Half-extents along the principal axes of the uniform box (or ellipsoid) with the same
    mass and principal moments; None without them. Tiny negative squares (rounding, or a
    flat part) become zero."""
    if properties.principal_moments is None or not properties.mass:
        return None
    i = np.asarray(properties.principal_moments, dtype=np.float64)
    factor = 3.0 if shape == "box" else 5.0
    squares = factor * (i.sum() - 2 * i) / (2 * abs(properties.mass))
    return np.sqrt(np.clip(squares, 0, None))


def inertia_layer(properties, shape: str = "box") -> Layer | None:
    """The equivalent uniform box (``shape="box"``) or ellipsoid, on the principal frame."""
    half = equivalent_half_extents(properties, shape)
    if half is None or properties.center_of_mass is None:
        return None
    axes = np.asarray(properties.principal_axes, dtype=np.float64)
    centre = np.asarray(properties.center_of_mass, dtype=np.float64)
    size = " x ".join(number(2 * h) for h in half)
    if shape == "box":
        segments = box_edges(-half, half) @ axes + centre       # rows of axes: the principal directions
        return Layer("inertia", f"equivalent uniform box {size}", segments=segments)
    segments = ellipse_edges(half) @ axes + centre
    return Layer("ellipsoid", f"equivalent uniform ellipsoid, axes {size}", segments=segments)


def bounds_layer(bounds) -> Layer:
    """The axis-aligned bounding box (a ``Bounds``)."""
    size = " x ".join(number(s) for s in bounds.size)
    return Layer("bounds", f"bounds {size}", segments=box_edges(bounds.min, bounds.max), width=1)


def box_edges(low, high) -> np.ndarray:
    """(12, 2, 3) the edges of the box ``[low, high]``."""
    low, high = np.asarray(low, dtype=np.float64), np.asarray(high, dtype=np.float64)
    corners = np.array([[high[k] if (c >> k) & 1 else low[k] for k in range(3)] for c in range(8)])
    pairs = [(a, a | (1 << k)) for a in range(8) for k in range(3) if not (a >> k) & 1]
    return np.array([[corners[a], corners[b]] for a, b in pairs])


def ellipse_edges(half, segments: int = 72) -> np.ndarray:
    """(3 segments, 2, 3) the three principal ellipses of an ellipsoid of semi-axes ``half``."""
    t = np.linspace(0, 2 * np.pi, segments + 1)
    out = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        ring = np.zeros((segments + 1, 3))
        ring[:, i] = half[i] * np.cos(t)
        ring[:, j] = half[j] * np.sin(t)
        out.append(np.stack([ring[:-1], ring[1:]], axis=1))
    return np.concatenate(out)
