"""Polyhedral volume integrals in exact rational arithmetic, for the shape-constant tests.

Independent of p3d's float code: each triangle (a, b, c) of a closed outward-wound surface
spans the signed tetrahedron (0, a, b, c), and with D = det[a b c] and s = a + b + c the
textbook simplex integrals are ∫dV = D/6, ∫x dV = D s/24, ∫x xᵀ dV = D (aaᵀ + bbᵀ + ccᵀ + ssᵀ)/120
(the Physics3D note's section 1.3 in closed form; docs/method.md, "Divergence theorem"). Coordinates are Fractions, so nothing rounds.
"""

from __future__ import annotations

from fractions import Fraction as F


def fan(faces):
    """Polygon faces (index lists) as triangles fanned from each face's first corner."""
    return [(f[0], f[k], f[k + 1]) for f in faces for k in range(1, len(f) - 1)]


def rational_moments(vertices, faces):
    """Exact (volume, centre, central second moments) of a closed polyhedron.

    Parameters
    ----------
    vertices : sequence of 3 rationals (int or Fraction)
    faces : sequence of index lists, counter-clockwise seen from outside

    Returns
    -------
    volume : Fraction
    center : tuple of 3 Fractions
    central : 3 × 3 tuple of Fractions, ∫ (x - c)(x - c)ᵀ dV
    """
    v = [tuple(F(x) for x in p) for p in vertices]
    six_v = F(0)
    first = [F(0)] * 3
    second = [[F(0)] * 3 for _ in range(3)]
    for i, j, k in fan(faces):
        a, b, c = v[i], v[j], v[k]
        d = (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2])
             + a[2] * (b[0] * c[1] - b[1] * c[0]))
        s = [a[m] + b[m] + c[m] for m in range(3)]
        six_v += d
        for m in range(3):
            first[m] += d * s[m]
            for n in range(3):
                second[m][n] += d * (a[m] * a[n] + b[m] * b[n] + c[m] * c[n] + s[m] * s[n])
    volume = six_v / 6
    center = tuple(f / 24 / volume for f in first)
    central = tuple(tuple(second[m][n] / 120 - volume * center[m] * center[n] for n in range(3))
                    for m in range(3))
    return volume, center, central


def directed_edges_pair_up(triangles) -> bool:
    """Every directed edge (by exact coordinates) has its reverse exactly once: closed, consistent."""
    from collections import Counter

    edges = Counter()
    for tri in triangles:
        pts = [tuple(map(float, p)) for p in tri]
        for k in range(3):
            edges[(pts[k], pts[(k + 1) % 3])] += 1
    return all(edges[(b, a)] == n for (a, b), n in edges.items())
