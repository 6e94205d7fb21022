"""Colours of the visible faces: flat Lambert shading under two lights, outlines where depth jumps.

Lights are fixed to the camera (so every view is lit alike): a key light from the upper left
and in front, a weaker fill from the right, an ambient term and a small white highlight. Faces
are shaded flat (one normal per face): a mesh's facets stay visible where they are large, and a
dense mesh looks smooth anyway. Both sides are lit; the side a face's winding points away from
the camera is tinted warm, so the inside of an open part seen through a hole, and faces wound
against their neighbours, show as such. A mesh wound inward as a whole (negative signed volume)
is turned around first, so that its outside is the outside.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.render.raster import DepthBuffer

BACKGROUND = (255, 255, 255)
#: Base colours (0-1) of the outer and the inner side of faces.
OUTSIDE = np.array([0.66, 0.72, 0.80])
INSIDE = np.array([0.82, 0.68, 0.55])
#: Outline colour, where the depth jumps (silhouettes, and steps between parts).
OUTLINE = np.array([0.20, 0.22, 0.26])

_KEY = np.array([-0.45, 0.55, 0.70])
_FILL = np.array([0.65, -0.25, 0.55])
_KEY /= np.linalg.norm(_KEY)
_FILL /= np.linalg.norm(_FILL)
_HALF = _KEY + np.array([0.0, 0.0, 1.0])
_HALF /= np.linalg.norm(_HALF)


def face_normals(triangles: np.ndarray) -> np.ndarray:
    """(n, 3) float32 unit normals of the faces by their winding (zero for degenerate faces)."""
    t = np.asarray(triangles, dtype=np.float32)
    normal = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    length = np.sqrt(np.einsum("ij,ij->i", normal, normal))
    length[length == 0] = 1.0
    return normal / length[:, None]


def signed_volume_sign(triangles: np.ndarray) -> float:
    """+1 when the faces enclose a positive signed volume (outward winding), else -1."""
    t = np.asarray(triangles, dtype=np.float64)
    centre = t.reshape(-1, 3).mean(axis=0)         # about the centre: fewer rounding errors
    a, b, c = t[:, 0] - centre, t[:, 1] - centre, t[:, 2] - centre
    volume = float(np.einsum("ij,ij->", a, np.cross(b, c)))
    return 1.0 if volume >= 0 else -1.0


def shade(buffer: DepthBuffer, view_normals: np.ndarray, scale: float) -> np.ndarray:
    """The shaded picture of the visible faces.

    Parameters
    ----------
    buffer : DepthBuffer
    view_normals : (n, 3) float
        Face normals in view coordinates (x right, y up, z towards the camera), outward.
    scale : float
        Pixels per unit length (to tell a depth jump from a slope).

    Returns
    -------
    (h, w, 3) uint8
    """
    # Flat shading: one colour per face (and the background last), looked up per pixel.
    table = np.empty((len(view_normals) + 1, 3), dtype=np.uint8)
    table[:-1] = np.clip(face_colours(view_normals) * 255 + 0.5, 0, 255).astype(np.uint8)
    table[-1] = BACKGROUND
    face = buffer.face
    image = table[np.where(face >= 0, face, len(view_normals))]
    _outline(image, buffer, scale)
    return image


def face_colours(view_normals: np.ndarray) -> np.ndarray:
    """(n, 3) float32 colours (0-1) of faces with the given view-space normals."""
    normal = np.asarray(view_normals, dtype=np.float32).copy()
    outside = normal[:, 2] >= 0
    normal[~outside] *= -1
    key = np.clip(normal @ _KEY.astype(np.float32), 0, None)
    fill = np.clip(normal @ _FILL.astype(np.float32), 0, None)
    glint = np.clip(normal @ _HALF.astype(np.float32), 0, None) ** 24
    light = 0.30 + 0.62 * key + 0.22 * fill
    base = np.where(outside[:, None], OUTSIDE.astype(np.float32), INSIDE.astype(np.float32))
    return base * light[:, None] + 0.18 * glint[:, None]


def _outline(image: np.ndarray, buffer: DepthBuffer, scale: float) -> None:
    """Darken pixels next to a jump in depth of more than a few pixels' worth (or to the
    background): silhouettes and the outlines of parts in front of others."""
    depth = buffer.depth.astype(np.float32)
    h, w = depth.shape
    jump = 4.0 / scale                       # four pixels' worth of depth
    edge = np.zeros(depth.shape, dtype=bool)
    for dy, dx in ((0, 1), (1, 0), (1, 1), (1, -1)):
        here, there = neighbours(h, w, dy, dx)
        a, b = depth[here], depth[there]
        with np.errstate(invalid="ignore"):
            step = np.abs(a - b) > jump      # inf - inf is nan: two empty pixels are no edge
        edge[here] |= step & (a <= b)        # darken the nearer side only
        edge[there] |= step & (b < a)
    edge &= buffer.face >= 0
    image[edge] = (image[edge] * 0.35 + OUTLINE * 255 * 0.65 + 0.5).astype(np.uint8)


def neighbours(h: int, w: int, dy: int, dx: int) -> tuple[tuple[slice, slice], tuple[slice, slice]]:
    """Slices ``here``, ``there`` of an (h, w) array such that ``a[there]`` is the neighbour at
    ``(+dy, +dx)`` of each pixel of ``a[here]`` (``dy >= 0``)."""
    rows_here, rows_there = slice(0, h - dy), slice(dy, h)
    if dx >= 0:
        return (rows_here, slice(0, w - dx)), (rows_there, slice(dx, w))
    return (rows_here, slice(-dx, w)), (rows_there, slice(0, w + dx))
