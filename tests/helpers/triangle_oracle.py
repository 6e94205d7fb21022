"""The slow, plainly exact reference for what two triangles do to each other (``Fraction``).

It computes the intersection itself -- the segments where each triangle meets the other's
plane, or the overlap polygon of coplanar triangles -- in rational arithmetic, and applies the
definitions of ``p3d_cli.mesh.triangle_pairs`` to it, without any of the orientation tricks
that module uses.
"""

from __future__ import annotations

from fractions import Fraction

NONE, CROSSING, OVERLAP, FOLD, CONTACT = 0, 1, 2, 3, 4


def _sub(a, b):
    return [x - y for x, y in zip(a, b)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def _sign(x) -> int:
    return (x > 0) - (x < 0)


def exact(T):
    return [[Fraction(x) for x in p] for p in T]


def shared_vertices(A, B) -> int:
    return sum(1 for a in A if any(list(a) == list(b) for b in B))


def classify(A, B) -> int:
    """The kind of the pair of non-degenerate triangles ``A``, ``B`` (three points each)."""
    A, B = exact(A), exact(B)
    shared = shared_vertices(A, B)
    if shared == 3:
        return NONE
    n_a = _cross(_sub(A[1], A[0]), _sub(A[2], A[0]))
    n_b = _cross(_sub(B[1], B[0]), _sub(B[2], B[0]))
    dist_b = [_dot(n_a, _sub(b, A[0])) for b in B]      # B's corners against A's plane
    dist_a = [_dot(n_b, _sub(a, B[0])) for a in A]
    s, t = [_sign(x) for x in dist_b], [_sign(x) for x in dist_a]
    for signs in (s, t):
        if all(x > 0 for x in signs) or all(x < 0 for x in signs):
            return NONE
    if all(x == 0 for x in s):
        if _overlap_area(A, B, n_a) == 0:
            return NONE
        if _dot(n_a, n_b) > 0:
            return OVERLAP
        return FOLD if shared == 2 else NONE
    direction = _cross(n_a, n_b)
    seg_a = _segment(A, dist_a, direction)
    seg_b = _segment(B, dist_b, direction)
    lo, hi = max(seg_a[0], seg_b[0]), min(seg_a[1], seg_b[1])
    if lo >= hi:
        return NONE                      # apart, or touching at one point
    straddle_a = 1 in t and -1 in t
    straddle_b = 1 in s and -1 in s
    if straddle_a and straddle_b:
        return CROSSING
    return NONE if shared == 2 else CONTACT


def _segment(T, dist, direction):
    """``T ∩`` the other plane, as the interval of ``direction · x`` it covers."""
    values = []
    for k in range(3):
        p, q = T[k], T[(k + 1) % 3]
        dp, dq = dist[k], dist[(k + 1) % 3]
        if dp == 0:
            values.append(_dot(direction, p))
        if (dp > 0 > dq) or (dp < 0 < dq):
            x = [p[i] + (q[i] - p[i]) * dp / (dp - dq) for i in range(3)]
            values.append(_dot(direction, x))
    return min(values), max(values)


def _overlap_area(A, B, normal) -> Fraction:
    """Twice the area of ``A ∩ B`` for coplanar triangles (Sutherland-Hodgman, exact)."""
    axis = max(range(3), key=lambda i: abs(normal[i]))
    keep = [(axis + 1) % 3, (axis + 2) % 3]
    a = [[p[i] for i in keep] for p in A]
    b = [[p[i] for i in keep] for p in B]
    if _area2(a) < 0:
        a = a[::-1]
    poly = b
    for k in range(3):
        p, q = a[k], a[(k + 1) % 3]
        poly = _clip(poly, p, q)
        if not poly:
            return Fraction(0)
    return abs(_area2(poly))


def _area2(poly):
    return sum(poly[i][0] * poly[(i + 1) % len(poly)][1] - poly[(i + 1) % len(poly)][0] * poly[i][1]
               for i in range(len(poly)))


def _side(p, q, x):
    return (q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0])


def _clip(poly, p, q):
    out = []
    for k in range(len(poly)):
        cur, nxt = poly[k], poly[(k + 1) % len(poly)]
        sc, sn = _side(p, q, cur), _side(p, q, nxt)
        if sc >= 0:
            out.append(cur)
        if (sc > 0 > sn) or (sc < 0 < sn):
            r = sc / (sc - sn)
            out.append([cur[i] + (nxt[i] - cur[i]) * r for i in range(2)])
    return out
