"""Vertices whose faces cannot meet each other beyond the vertex and its edges: a certificate.

Most face pairs of a mesh whose boxes overlap are neighbours: faces around one vertex. For a
vertex ``v`` of a closed, manifold mesh, its faces form one fan. Choose a direction ``N``
(their normals summed; any direction works, the tests below are exact for the one chosen)
and look along it: each face ``(v, b, c)`` covers the angular sector from ``b - v`` to
``c - v`` around ``v``. If every face turns counter-clockwise seen along ``N`` (``det[b - v,
c - v, N] > 0``), consecutive faces share their boundary directions and the fan's sectors
wrap around ``v`` a whole number of times; if a reference direction ``R`` (perpendicular to
``N``) lies in exactly one sector, they wrap once, and the sectors tile the plane around ``v``.
The faces, projected along ``N``, then meet only where they share an edge (consecutive) or
only at ``v`` (the others); as each face projects one to one, the faces themselves meet only
there. So no pair of faces around ``v`` needs the pair test. The sector test counts ``R`` in
the half-open sector ``[b - v, c - v)``: ``det[b - v, R, N] >= 0`` and ``det[R, c - v, N] > 0``;
a zero among them (``R`` along an edge, as seen) leaves the vertex to the pair test.

Every sign is exact (``p3d_cli.geometry.predicates``); the certificate is one determinant of
each kind per corner, fewer operations than the pair tests it replaces (about a dozen pairs
per face), and it needs no order of the faces around the vertex.

With the compiled kernels (``p3d_cli.mesh.kernels``) both passes run there, the same float
operations in the same order; the corners whose signs the float filter leaves unsure come
back and take the exact road below, so the certified vertices are the same either way.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.predicates import O3D_BOUND, Planes, turn
from p3d_cli.mesh.kernels import compiled, key_buffer, sort

#: Corners per vectorised step.
_STEP = 1 << 15
#: Two fixed directions, far from the axes and from each other, for the reference ``R = N × G``.
_G = (np.array([0.6180339887498949, 0.3819660112501051, 0.7071067811865476]),
      np.array([-0.2679491924311227, 0.8660254037844386, 0.4226182617406994]))


def certified_vertices(points: np.ndarray, faces: np.ndarray, safe: bool = True) -> np.ndarray:
    """Which vertices have a fan of faces that meet only at the vertex and along shared edges.

    Parameters
    ----------
    points : (m, 3) float64
    faces : (n, 3) int
        A closed mesh without non-manifold vertices or edges: every vertex's faces form one
        fan (the caller's condition; elsewhere the counting below proves nothing, except at
        the ``paired_vertices``, whose faces form closed fans: one wrap in all is one fan).
    safe : bool
        ``predicates.in_safe_range(points)``.

    Returns
    -------
    (m,) bool
    """
    m = len(points)
    normal = np.zeros((m, 3))
    # N is only a chosen direction (the tests are exact for whichever one): summed from the
    # points scaled by a power of two to a span near 1, it neither over- nor underflows.
    span = float(np.abs(points).max()) if m else 0.0
    shift = -int(np.frexp(span)[1]) if 0 < span < np.inf else 0
    fast = compiled()
    if fast is not None and safe and m and len(faces):
        certified = _compiled(fast, points, faces, shift, normal)
        if certified is not None:
            return certified
        normal[:] = 0.0
    for start in range(0, len(faces), _STEP):
        f = faces[start:start + _STEP]
        with np.errstate(under="ignore"):
            a, b, c = (np.ldexp(np.take(points, f[:, k], axis=0), shift) for k in range(3))
        n = np.repeat(np.cross(b - a, c - a), 3, axis=0)
        # Vertices are numbered by use, so a chunk's ids span a short range: bincount there.
        ids = f.ravel()
        low = int(ids.min())
        width = int(ids.max()) - low + 1
        for k in range(3):
            normal[low:low + width, k] += np.bincount(ids - low, weights=n[:, k], minlength=width)
    good = np.ones(m, dtype=bool)
    hits = []
    for start in range(0, len(faces), _STEP):
        f = faces[start:start + _STEP]
        corner = [np.take(points, f[:, k], axis=0) for k in range(3)]
        for k in range(3):
            v = f[:, k]
            P, B, C = corner[k], corner[(k + 1) % 3], corner[(k + 2) % 3]
            # The reference and the minors of (R, N), per corner: per vertex they would cost
            # four arrays of the vertices' size at once (memory), for no time saved.
            N = np.take(normal, v, axis=0)
            R = _reference(N)
            M, Mabs = _minors(R, N)
            x, y = B - P, C - P
            sector = _sector(x, y, N, P, B, C, safe)        # det[b - v, c - v, N]
            before = _turn(x, M, Mabs, P, B, R, N, safe)    # det[b - v, R, N]
            after = -_turn(y, M, Mabs, P, C, R, N, safe)    # det[R, c - v, N]
            bad = (sector <= 0) | (before == 0) | (after == 0)
            good[v[bad]] = False
            hits.append(v[(before > 0) & (after > 0)])
    count = np.bincount(np.concatenate(hits), minlength=m) if hits else np.zeros(m, dtype=np.int64)
    return good & (count == 1)


def paired_vertices(faces: np.ndarray, m: int) -> np.ndarray:
    """Which of the ``m`` vertices have every edge paired once each way: around ``v``, each
    neighbour is the second corner after ``v`` of exactly one face and the third of exactly
    one (faces ``(v, b, c)`` read from ``v``). The faces around such a vertex then form closed
    fans, each face's sides shared with the next, however open or non-manifold the mesh is
    elsewhere, and ``certified_vertices``'s count (one wrap in all) proves them. A vertex on a
    boundary, misoriented or non-manifold edge, or of a face with a repeated corner, is not.

    Exact: the keys ``(v, b)`` and ``(v, c)`` of every corner sorted (a vertex has as many of
    each), equal position by position and ``(v, b)`` never twice.
    """
    faces = np.asarray(faces)
    if m == 0 or len(faces) == 0:
        return np.zeros(m, dtype=bool)
    bits = max(int(m - 1).bit_length(), 1)
    if 2 * bits > 63:
        return np.zeros(m, dtype=bool)
    good = np.ones(m, dtype=bool)
    out, into = key_buffer(3 * len(faces)), key_buffer(3 * len(faces))
    for start in range(0, len(faces), _STEP):            # bounded temporaries
        f = faces[start:start + _STEP].astype(np.int64)
        v = f.ravel() << bits
        out[3 * start:3 * start + v.size] = (v | np.roll(f, -1, axis=1).ravel()).view(np.uint64)
        into[3 * start:3 * start + v.size] = (v | np.roll(f, -2, axis=1).ravel()).view(np.uint64)
        # A face with a repeated corner: an edge (v, v).
        good[f[(f[:, 0] == f[:, 1]) | (f[:, 1] == f[:, 2]) | (f[:, 2] == f[:, 0])].ravel()] = False
    sort(out)
    sort(into)
    top = np.uint64(bits)
    good[(out[np.flatnonzero(out != into)] >> top).astype(np.int64)] = False
    good[(out[np.flatnonzero(out[1:] == out[:-1])] >> top).astype(np.int64)] = False
    return good


def _compiled(fast, points, faces, shift: int, normal: np.ndarray) -> np.ndarray | None:
    """``certified_vertices`` by the compiled kernels (``safe`` points), or None when more
    corners than it keeps room for were unsure (the numpy road then does them all)."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    faces = np.ascontiguousarray(faces)
    if faces.dtype not in (np.int32, np.int64):
        faces = faces.astype(np.int64)
    fast.star_normals(points, faces, shift, _STEP, normal)
    m = len(points)
    good = np.ones(m, dtype=bool)
    count = np.zeros(m, dtype=np.int64)
    deferred = np.empty(max(1 << 12, len(faces) // 8), dtype=np.int64)
    unsure = fast.star_signs(points, faces, normal, O3D_BOUND, tuple(_G[0]), tuple(_G[1]), good.view(np.uint8),
                             count, deferred)
    if unsure < 0:
        return None
    if unsure:
        # The corners the filter left unsure: the numpy road's signs, exact where they must be.
        corner = deferred[:unsure]
        f, k = faces[corner // 3], corner % 3
        rows = np.arange(unsure)
        v = f[rows, k]
        P, B, C = (np.take(points, f[rows, (k + s) % 3], axis=0) for s in range(3))
        N = np.take(normal, v, axis=0)
        R = _reference(N)
        M, Mabs = _minors(R, N)
        x, y = B - P, C - P
        sector = _sector(x, y, N, P, B, C, True)
        before = _turn(x, M, Mabs, P, B, R, N, True)
        after = -_turn(y, M, Mabs, P, C, R, N, True)
        good[v[(sector <= 0) | (before == 0) | (after == 0)]] = False
        count += np.bincount(v[(before > 0) & (after > 0)], minlength=m)
    return good & (count == 1)


def _sector(x, y, n, a, b, c, safe: bool) -> np.ndarray:
    """``det[x, y, n]`` for the rounded differences ``x = b - a``, ``y = c - a`` and an exact
    ``n``: the minors of ``x, y`` dotted with ``n`` (Shewchuk's structure and bound)."""
    if not safe:
        return Planes(a, b, c, safe).facing(n)
    p0, p1 = x[:, 1] * y[:, 2], x[:, 2] * y[:, 1]
    p2, p3 = x[:, 2] * y[:, 0], x[:, 0] * y[:, 2]
    p4, p5 = x[:, 0] * y[:, 1], x[:, 1] * y[:, 0]
    det = ((p0 - p1) * n[:, 0] + (p2 - p3) * n[:, 1]) + (p4 - p5) * n[:, 2]
    perm = ((np.abs(p0) + np.abs(p1)) * np.abs(n[:, 0]) + (np.abs(p2) + np.abs(p3)) * np.abs(n[:, 1])
            + (np.abs(p4) + np.abs(p5)) * np.abs(n[:, 2]))
    out = (det > 0).view(np.int8) - (det < 0).view(np.int8)
    unsure = np.flatnonzero((np.abs(det) <= O3D_BOUND * perm) & (perm != 0))
    if unsure.size:
        out[unsure] = Planes(a[unsure], b[unsure], c[unsure], safe).facing(n[unsure])
    return out


def _reference(normal: np.ndarray) -> np.ndarray:
    """``R = N × G``, with the second ``G`` where the first is nearly along ``N``."""
    reference = np.cross(normal, _G[0])
    weak = np.abs(reference).sum(axis=1) < 0.25 * np.abs(normal).sum(axis=1)
    if weak.any():
        reference[weak] = np.cross(normal[weak], _G[1])
    return reference


def _minors(r: np.ndarray, n: np.ndarray):
    """``r × n`` as Shewchuk's stage A rounds it, and the sums of its products' magnitudes."""
    p = (r[:, 1] * n[:, 2], r[:, 2] * n[:, 1], r[:, 2] * n[:, 0], r[:, 0] * n[:, 2], r[:, 0] * n[:, 1],
         r[:, 1] * n[:, 0])
    minor = np.stack([p[0] - p[1], p[2] - p[3], p[4] - p[5]], axis=1)
    minor_abs = np.stack([np.abs(p[0]) + np.abs(p[1]), np.abs(p[2]) + np.abs(p[3]), np.abs(p[4]) + np.abs(p[5])],
                         axis=1)
    return minor, minor_abs


def _turn(x, minor, minor_abs, a, b, r, n, safe: bool) -> np.ndarray:
    """``predicates.turn(a, b, r, n)`` from ``x = b - a`` and the minors of ``r`` and ``n``."""
    if not safe:
        return turn(a, b, r, n, safe)
    det = (x[:, 0] * minor[:, 0] + x[:, 1] * minor[:, 1]) + x[:, 2] * minor[:, 2]
    ax = np.abs(x)
    perm = (ax[:, 0] * minor_abs[:, 0] + ax[:, 1] * minor_abs[:, 1]) + ax[:, 2] * minor_abs[:, 2]
    out = (det > 0).view(np.int8) - (det < 0).view(np.int8)
    unsure = np.flatnonzero((np.abs(det) <= O3D_BOUND * perm) & (perm != 0))
    if unsure.size:
        out[unsure] = turn(a[unsure], b[unsure], r[unsure], n[unsure], safe)
    return out
