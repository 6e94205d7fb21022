"""Open meshes still give an answer, said to be one: a thin shell, or the convex hull's solid.

A link whose mesh is open (boundary edges), non-manifold or inward-wound bounds no solid, so
its volume integrals mean nothing. Two stand-ins, chosen by the caller (``open_mesh``):

- ``"hull"``: each such mesh is replaced by its convex hull (Qhull, through scipy: the
  ``robots`` extra), a closed solid measured like any other (density or mass). Right for
  convex or nearly convex parts; it overstates the volume of concave ones.
- ``"shell"``: the whole link is a thin shell, its mass spread evenly over the surface of every
  geom (meshes by their triangles, primitives by a fine tessellation of 96 segments). The
  mass must be given (a declared mass or a table): a surface has no volume for a density.
  A triangle's area moments are exact (``∫ x xᵀ dA = A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ)``,
  ``s = a + b + c``: the second moments of a triangle, Eberly, "Polyhedral Mass Properties").

``"refuse"`` (the default) keeps such a link unmeasured, with a message naming the others.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import InputError, MissingExtraError, install_hint
from p3d_cli.results import MassProperties

#: What ``open_mesh`` may be.
OPEN_MESH = ("refuse", "shell", "hull")
#: Segments of a primitive's tessellation in a shell.
SEGMENTS = 96


def hull_triangles(triangles: np.ndarray, where: str) -> np.ndarray:
    """The convex hull of the triangles' corners as outward-wound triangles.

    Parameters
    ----------
    triangles : (n, 3, 3) float
    where : str
        The geom, for messages.

    Returns
    -------
    (m, 3, 3) float64

    Raises
    ------
    MissingExtraError
        scipy is not installed.
    InputError
        The corners are flat (no hull of volume).
    """
    try:
        from scipy.spatial import ConvexHull, QhullError
    except ImportError:
        raise MissingExtraError(where, "the convex hull of an open mesh needs scipy",
                                install_hint("robots", "'scipy>=1.10'")) from None
    points = np.unique(np.asarray(triangles, dtype=np.float64).reshape(-1, 3), axis=0)
    try:
        hull = ConvexHull(points)
    except (QhullError, ValueError):
        raise InputError(where, "the mesh is flat or has too few corners for a convex hull",
                         "give it a solid mesh, or use a shell") from None
    corners = points[hull.simplices]
    # Qhull's facets come in any winding: turn each to face along its outward plane normal.
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    inward = np.einsum("ij,ij->i", normals, hull.equations[:, :3]) < 0
    corners[inward] = corners[inward][:, ::-1]
    return corners


def shell_properties(triangles: np.ndarray, mass: float, where: str) -> MassProperties:
    """The mass properties of a uniform thin shell of total ``mass`` over the triangles.

    Raises
    ------
    InputError
        The surface has no area.
    """
    from p3d_cli.geometry.inertia import (inertia_from_second_moments, principal_frame, principal_rotation,
                                          shifted_inertia)

    t = np.asarray(triangles, dtype=np.float64)
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    areas = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    area = float(areas.sum())
    if not area > 0 or not np.isfinite(area):
        raise InputError(where, "the surface has no area for a shell", "give it geometry with area")
    s = a + b + c
    center = (areas[:, None] * s).sum(axis=0) / (3 * area)
    # About the centre: shift every corner first, so that no large offset cancels.
    a, b, c, s = a - center, b - center, c - center, s - 3 * center
    outer = lambda u: np.einsum("ni,nj->nij", u, u)
    second_area = (areas[:, None, None] * (outer(a) + outer(b) + outer(c) + outer(s))).sum(axis=0) / 12
    sigma = mass / area
    second = sigma * second_area
    inertia = inertia_from_second_moments(second)
    principal, axes = principal_frame(inertia)
    origin = shifted_inertia(inertia, mass, center, np.zeros(3))
    return MassProperties(0.0, sigma, float(mass), center, inertia, origin, principal, axes, second,
                          **principal_rotation(axes))


def placed_triangles(solid, placement) -> np.ndarray:
    """A geom's surface triangles in the link frame: mesh triangles, or a primitive's
    polyhedron or tessellation, scaled, turned and moved by the placement."""
    if solid.mesh is not None:
        t = np.asarray(solid.mesh.triangles(), dtype=np.float64)
    elif hasattr(solid.shape, "triangles"):
        t = np.asarray(solid.shape.triangles(), dtype=np.float64)
    else:
        t = np.asarray(solid.shape.tessellate(SEGMENTS), dtype=np.float64)
    if placement.scale is not None:
        t = t * np.asarray(placement.scale, dtype=np.float64)
    if placement.rotation is not None:
        t = t @ np.asarray(placement.rotation, dtype=np.float64).T
    if placement.translation is not None:
        t = t + np.asarray(placement.translation, dtype=np.float64)
    return t
