"""Per-body float kernels of the small step: a body's turn, and its inertia in the world frame.

``turn`` (the drift's rotation, renormalised) and ``nudge`` (the position correction's small
turns) update a quaternion and give its matrix; ``carry_spin*`` carry the angular velocity
through a turn at constant angular momentum; ``conjugate*`` give the world inverse inertia
``R I⁻¹ Rᵀ``. Each comes in the general form and in cheaper ones for the commonest bodies:
principal-axis (diagonal) inertias, and bodies of revolution (two equal moments: rods, links,
cylinders, capsules, square-section bars). See ``scalar`` for conventions: vectors 3 floats,
matrices 9 floats row-major, quaternions ``[w, x, y, z]``.
"""

from __future__ import annotations

import math


def carry_spin(r, t, inertia, inv_inertia, w) -> tuple[float, float, float]:
    """``T I⁻¹ Tᵀ (R I Rᵀ ω)``: the angular velocity that keeps the angular momentum
    ``I_world ω`` through a turn from ``R`` to ``T`` (``World.drift``), as six matrix-vector
    products written out (one call instead of six)."""
    w0, w1, w2 = w
    a0, a1, a2 = r[0] * w0 + r[3] * w1 + r[6] * w2, r[1] * w0 + r[4] * w1 + r[7] * w2, r[2] * w0 + r[5] * w1 + r[8] * w2
    m = inertia
    b0, b1, b2 = m[0] * a0 + m[1] * a1 + m[2] * a2, m[3] * a0 + m[4] * a1 + m[5] * a2, m[6] * a0 + m[7] * a1 + m[8] * a2
    s0, s1, s2 = r[0] * b0 + r[1] * b1 + r[2] * b2, r[3] * b0 + r[4] * b1 + r[5] * b2, r[6] * b0 + r[7] * b1 + r[8] * b2
    a0, a1, a2 = t[0] * s0 + t[3] * s1 + t[6] * s2, t[1] * s0 + t[4] * s1 + t[7] * s2, t[2] * s0 + t[5] * s1 + t[8] * s2
    m = inv_inertia
    b0, b1, b2 = m[0] * a0 + m[1] * a1 + m[2] * a2, m[3] * a0 + m[4] * a1 + m[5] * a2, m[6] * a0 + m[7] * a1 + m[8] * a2
    return (t[0] * b0 + t[1] * b1 + t[2] * b2, t[3] * b0 + t[4] * b1 + t[5] * b2, t[6] * b0 + t[7] * b1 + t[8] * b2)


def carry_spin_diagonal(r, t, d, e, w) -> tuple[float, float, float]:
    """``carry_spin`` for a diagonal inertia ``diag(d)`` (inverse ``diag(e)``): the same numbers
    (the general form's products with its zero entries add exact zeros), in 60% of the work."""
    w0, w1, w2 = w
    a0 = d[0] * (r[0] * w0 + r[3] * w1 + r[6] * w2)
    a1 = d[1] * (r[1] * w0 + r[4] * w1 + r[7] * w2)
    a2 = d[2] * (r[2] * w0 + r[5] * w1 + r[8] * w2)
    s0, s1, s2 = r[0] * a0 + r[1] * a1 + r[2] * a2, r[3] * a0 + r[4] * a1 + r[5] * a2, r[6] * a0 + r[7] * a1 + r[8] * a2
    a0 = e[0] * (t[0] * s0 + t[3] * s1 + t[6] * s2)
    a1 = e[1] * (t[1] * s0 + t[4] * s1 + t[7] * s2)
    a2 = e[2] * (t[2] * s0 + t[5] * s1 + t[8] * s2)
    return (t[0] * a0 + t[1] * a1 + t[2] * a2, t[3] * a0 + t[4] * a1 + t[5] * a2, t[6] * a0 + t[7] * a1 + t[8] * a2)


def axis_of_revolution(d, e):
    """``(j, d_a, d_j, e_a, e_j)`` for a diagonal inertia ``diag(d)`` (inverse ``diag(e)``) with
    two equal moments ``d_a`` across body axis ``j`` (its moment ``d_j``), else None. A sphere
    (three equal) is one too, about z."""
    for j, (a, b) in ((2, (0, 1)), (1, (0, 2)), (0, (1, 2))):
        if d[a] == d[b] and e[a] == e[b]:
            return j, d[a], d[j], e[a], e[j]
    return None


def carry_spin_axial(z, t, axial, w) -> tuple[float, float, float]:
    """``carry_spin`` for a body of revolution (``axis_of_revolution``), from its axis before
    (``z``, the ``j``-th column of ``R``) and after the turn (``t``): ``R I Rᵀ = d_a E +
    (d_j - d_a) z zᵀ``, so the angular momentum is ``d_a ω + (d_j - d_a)(z·ω) z`` and the new
    ``ω`` the same with ``t`` and ``e``: the same numbers to rounding (the two forms agree for
    any orthogonal ``R``; ``R`` is orthogonal to rounding) in 60% of ``carry_spin_diagonal``'s
    time."""
    _, da, dj, ea, ej = axial
    w0, w1, w2 = w
    z0, z1, z2 = z
    s = (dj - da) * (z0 * w0 + z1 * w1 + z2 * w2)
    l0, l1, l2 = da * w0 + s * z0, da * w1 + s * z1, da * w2 + s * z2
    z0, z1, z2 = t
    s = (ej - ea) * (z0 * l0 + z1 * l1 + z2 * l2)
    return ea * l0 + s * z0, ea * l1 + s * z1, ea * l2 + s * z2


def conjugate_axial(z, axial) -> list[float]:
    """``conjugate(r, diag(e))`` for a body of revolution of axis ``z``: ``e_a E + (e_j - e_a)
    z zᵀ`` (see ``carry_spin_axial``), symmetric by construction, in half
    ``conjugate_diagonal``'s time."""
    _, _, _, ea, ej = axial
    z0, z1, z2 = z
    c = ej - ea
    a0, a1, a2 = c * z0, c * z1, c * z2
    xy, xz, yz = a0 * z1, a0 * z2, a1 * z2
    return [ea + a0 * z0, xy, xz, xy, ea + a1 * z1, yz, xz, yz, ea + a2 * z2]


def conjugate_diagonal(r, e) -> list[float]:
    """``conjugate(r, diag(e))``, the same numbers in half the work."""
    a0, a1, a2 = r[0] * e[0], r[1] * e[1], r[2] * e[2]
    b0, b1, b2 = r[3] * e[0], r[4] * e[1], r[5] * e[2]
    c0, c1, c2 = r[6] * e[0], r[7] * e[1], r[8] * e[2]
    xx = a0 * r[0] + a1 * r[1] + a2 * r[2]
    xy = a0 * r[3] + a1 * r[4] + a2 * r[5]
    xz = a0 * r[6] + a1 * r[7] + a2 * r[8]
    yy = b0 * r[3] + b1 * r[4] + b2 * r[5]
    yz = b0 * r[6] + b1 * r[7] + b2 * r[8]
    zz = c0 * r[6] + c1 * r[7] + c2 * r[8]
    return [xx, xy, xz, xy, yy, yz, xz, yz, zz]


def conjugate(r, m) -> list[float]:
    """``R M Rᵀ`` for a symmetric ``M`` (a world inverse inertia), symmetric by construction."""
    a = [r[0] * m[0] + r[1] * m[3] + r[2] * m[6], r[0] * m[1] + r[1] * m[4] + r[2] * m[7],
         r[0] * m[2] + r[1] * m[5] + r[2] * m[8],
         r[3] * m[0] + r[4] * m[3] + r[5] * m[6], r[3] * m[1] + r[4] * m[4] + r[5] * m[7],
         r[3] * m[2] + r[4] * m[5] + r[5] * m[8],
         r[6] * m[0] + r[7] * m[3] + r[8] * m[6], r[6] * m[1] + r[7] * m[4] + r[8] * m[7],
         r[6] * m[2] + r[7] * m[5] + r[8] * m[8]]
    xx = a[0] * r[0] + a[1] * r[1] + a[2] * r[2]
    xy = a[0] * r[3] + a[1] * r[4] + a[2] * r[5]
    xz = a[0] * r[6] + a[1] * r[7] + a[2] * r[8]
    yy = a[3] * r[3] + a[4] * r[4] + a[5] * r[5]
    yz = a[3] * r[6] + a[4] * r[7] + a[5] * r[8]
    zz = a[6] * r[6] + a[7] * r[7] + a[8] * r[8]
    return [xx, xy, xz, xy, yy, yz, xz, yz, zz]


def turn(q, rx: float, ry: float, rz: float, column: int | None = None):
    """``(q', R(q'))`` with ``q' = exp(θ) ⊗ q`` renormalised (``rotation.rotate_by_many`` for one
    body) and ``R`` its matrix in the homogeneous form of ``p3d_cli.geometry.rotation.quaternion_matrix``
    (exact at quarter turns), the two always wanted together, in one call. With ``column``,
    only that column of ``R`` (3 floats; the same numbers), for a body nothing reads more of.

    A rotation that overflowed gives nan (as numpy does), which the step's finiteness check
    reports: ``math.sin`` of an infinite angle would raise instead."""
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    qw, qx, qy, qz = q
    if angle >= 1e-8:
        if angle == math.inf:
            return (math.nan,) * 4, [math.nan] * (9 if column is None else 3)
        half = 0.5 * angle
        factor = math.sin(half) / angle
        pw, px, py, pz = math.cos(half), factor * rx, factor * ry, factor * rz
        w = pw * qw - px * qx - py * qy - pz * qz
        x = pw * qx + px * qw + py * qz - pz * qy
        y = pw * qy - px * qz + py * qw + pz * qx
        z = pw * qz + px * qy - py * qx + pz * qw
    else:
        # The small turns of the position correction: below 1e-8, cos(angle / 2) is 1 - (at
        # most) 1.25e-17, which rounds to 1.0, and products with 1.0 are exact: the same numbers.
        factor = 0.5 - angle * angle / 48.0
        px, py, pz = factor * rx, factor * ry, factor * rz
        w = qw - px * qx - py * qy - pz * qz
        x = qx + px * qw + py * qz - pz * qy
        y = qy - px * qz + py * qw + pz * qx
        z = qz + px * qy - py * qx + pz * qw
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    n = ww + xx + yy + zz
    if column is not None:
        # The column's expressions of the matrix below (written out: a call costs as much).
        if column == 2:
            c0, c1, c2 = 2 * (x * z + w * y), 2 * (y * z - w * x), ww - xx - yy + zz
        elif column == 0:
            c0, c1, c2 = ww + xx - yy - zz, 2 * (x * y + w * z), 2 * (x * z - w * y)
        else:
            c0, c1, c2 = 2 * (x * y - w * z), ww - xx + yy - zz, 2 * (y * z + w * x)
        return (w, x, y, z), [c0, c1, c2] if n == 1.0 else [c0 / n, c1 / n, c2 / n]
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    # 2 a ± 2 b written 2 (a ± b): doubling is exact, so these are the same numbers in fewer
    # operations; and a division by an n of exactly 1 (often, after the normalisation) is skipped.
    if n == 1.0:
        return (w, x, y, z), [ww + xx - yy - zz, 2 * (xy - wz), 2 * (xz + wy), 2 * (xy + wz), ww - xx + yy - zz,
                              2 * (yz - wx), 2 * (xz - wy), 2 * (yz + wx), ww - xx - yy + zz]
    return (w, x, y, z), [(ww + xx - yy - zz) / n, 2 * (xy - wz) / n, 2 * (xz + wy) / n,
                          2 * (xy + wz) / n, (ww - xx + yy - zz) / n, 2 * (yz - wx) / n,
                          2 * (xz - wy) / n, 2 * (yz + wx) / n, (ww - xx - yy + zz) / n]


def nudge(q, dx: float, dy: float, dz: float, column: int | None = None):
    """``turn(q, -dx, -dy, -dz)`` to rounding, for the position correction's small turns (by
    minus its motion ``d``), in two thirds of the work: ``(q', R(q'))``.

    Below an angle of 1e-4 (``s = |d|² < 1e-8``) the series ``cos(θ/2) = 1 - s/8`` and
    ``sin(θ/2)/θ = 1/2 - s/48`` leave out terms under ``s²/384 < 3e-19``, far below a float's
    rounding, so no square root, sine or cosine is needed; ``q'`` is not renormalised (``|exp|``
    is 1 to the same 3e-19, so ``|q'|`` is ``|q|`` to rounding, and the next drift's ``turn``
    renormalises), and the matrix is the homogeneous form, a rotation whatever ``|q'|``.
    A larger or non-finite turn is ``turn``'s. ``column`` as for ``turn``.
    """
    s = dx * dx + dy * dy + dz * dz
    if not s < 1e-8:
        return turn(q, -dx, -dy, -dz, column)
    c = 1.0 - 0.125 * s
    f = s / 48.0 - 0.5          # minus sin(θ/2)/θ: the turn is by -d
    px, py, pz = f * dx, f * dy, f * dz
    qw, qx, qy, qz = q
    w = c * qw - px * qx - py * qy - pz * qz
    x = c * qx + px * qw + py * qz - pz * qy
    y = c * qy - px * qz + py * qw + pz * qx
    z = c * qz + px * qy - py * qx + pz * qw
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    one = 1.0 / (ww + xx + yy + zz)
    if column is not None:
        # The column's expressions of the matrix below, as in turn.
        two = one + one
        if column == 2:
            return (w, x, y, z), [(x * z + w * y) * two, (y * z - w * x) * two, (ww - xx - yy + zz) * one]
        if column == 0:
            return (w, x, y, z), [(ww + xx - yy - zz) * one, (x * y + w * z) * two, (x * z - w * y) * two]
        return (w, x, y, z), [(x * y - w * z) * two, (ww - xx + yy - zz) * one, (y * z + w * x) * two]
    two = one + one
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    return (w, x, y, z), [(ww + xx - yy - zz) * one, (xy - wz) * two, (xz + wy) * two,
                          (xy + wz) * two, (ww - xx + yy - zz) * one, (yz - wx) * two,
                          (xz - wy) * two, (yz + wx) * two, (ww - xx - yy + zz) * one]
