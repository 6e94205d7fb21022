"""A point where two faces meet, in rational arithmetic (for the few pairs a report shows)."""

from __future__ import annotations

from fractions import Fraction

from p3d_cli.geometry.rational import cross, dot, sub





def meeting_point(A, B) -> tuple[float, float, float]:
    """A point of ``A ∩ B`` (two triangles given as three points each) that is not merely a
    shared vertex: the middle of the common segment of non-coplanar faces, the centre of the
    overlap of coplanar ones. Rounded once to float64."""
    A = [[Fraction(float(x)) for x in p] for p in A]
    B = [[Fraction(float(x)) for x in p] for p in B]
    n_a = cross(sub(A[1], A[0]), sub(A[2], A[0]))
    n_b = cross(sub(B[1], B[0]), sub(B[2], B[0]))
    direction = cross(n_a, n_b)
    if any(direction):
        ends_a = _plane_cut(A, [dot(n_b, sub(p, B[0])) for p in A])
        ends_b = _plane_cut(B, [dot(n_a, sub(p, A[0])) for p in B])
        key = lambda p: dot(direction, p)
        lo = max(min(ends_a, key=key), min(ends_b, key=key), key=key)
        hi = min(max(ends_a, key=key), max(ends_b, key=key), key=key)
        point = [(x + y) / 2 for x, y in zip(lo, hi)]
    else:
        point = _overlap_centre(A, B, n_a)
    return (float(point[0]), float(point[1]), float(point[2]))


def _plane_cut(T, dist) -> list:
    """The points where triangle ``T`` meets a plane (signed distances ``dist`` of its corners)."""
    out = []
    for k in range(3):
        p, q = T[k], T[(k + 1) % 3]
        dp, dq = dist[k], dist[(k + 1) % 3]
        if dp == 0:
            out.append(p)
        if (dp > 0 > dq) or (dp < 0 < dq):
            out.append([p[i] + (q[i] - p[i]) * dp / (dp - dq) for i in range(3)])
    return out or list(T)


def _overlap_centre(A, B, normal):
    """The vertex average of the (convex) overlap of coplanar triangles, back in 3-D."""
    axis = max(range(3), key=lambda i: abs(normal[i]))
    keep = [(axis + 1) % 3, (axis + 2) % 3]
    a = [[p[i] for i in keep] for p in A]
    poly = [[p[i] for i in keep] for p in B]
    if _area2(a) < 0:
        a = a[::-1]
    for k in range(3):
        poly = _clip(poly, a[k], a[(k + 1) % 3])
        if not poly:
            poly = [a[0]]
            break
    u = sum(p[0] for p in poly) / len(poly)
    v = sum(p[1] for p in poly) / len(poly)
    point = [Fraction(0)] * 3
    point[keep[0]], point[keep[1]] = u, v
    # On the plane: normal · (x - A0) = 0 fixes the dropped coordinate.
    rest = sum(normal[i] * (point[i] - A[0][i]) for i in keep)
    point[axis] = A[0][axis] - rest / normal[axis]
    return point


def _area2(poly):
    return sum(poly[i][0] * poly[(i + 1) % len(poly)][1] - poly[(i + 1) % len(poly)][0] * poly[i][1]
               for i in range(len(poly)))


def _clip(poly, p, q):
    """Sutherland-Hodgman: the part of ``poly`` left of the line ``p -> q``."""
    out = []
    side = lambda x: (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0])
    for k in range(len(poly)):
        cur, nxt = poly[k], poly[(k + 1) % len(poly)]
        sc, sn = side(cur), side(nxt)
        if sc >= 0:
            out.append(cur)
        if (sc > 0 > sn) or (sc < 0 < sn):
            r = sc / (sc - sn)
            out.append([cur[i] + (nxt[i] - cur[i]) * r for i in range(2)])
    return out
