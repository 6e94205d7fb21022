"""Independent mass properties of the arm's links: closed forms and a tetrahedron sum in numpy,
placed by hand (no p3d code), for the tests to compare p3d's robot readers with."""

from __future__ import annotations

import numpy as np

from helpers.robot_arm import BOX_MM, DENSITY, RPY_WEDGE, WEDGE_FACES, WEDGE_MM, YAW_BOX


def rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def ry(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def rx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def rpy(r, p, y):
    """URDF: R = Rz(y) Ry(p) Rx(r)."""
    return rz(y) @ ry(p) @ rx(r)


def mesh_body(vertices, faces, density):
    """Mass, centre and inertia (about the centre) of a closed mesh: a sum over the tetrahedra
    (origin, a, b, c), each with ∫ x xᵀ dV = V/20 (Σ vᵢvᵢᵀ + (Σ vᵢ)(Σ vᵢ)ᵀ) over its corners."""
    volume, first, second = 0.0, np.zeros(3), np.zeros((3, 3))
    for a, b, c in vertices[faces]:
        v = np.dot(a, np.cross(b, c)) / 6.0
        corners = [np.zeros(3), a, b, c]
        total = sum(corners)
        volume += v
        first += v * total / 4.0
        second += v / 20.0 * (sum(np.outer(p, p) for p in corners) + np.outer(total, total))
    center = first / volume
    central = second - volume * np.outer(center, center)
    s = density * central
    return density * volume, center, np.trace(s) * np.eye(3) - s


def placed(body, rotation, translation):
    m, c, i = body
    return m, rotation @ c + translation, rotation @ i @ rotation.T


def combined(bodies):
    """Sum with the parallel-axis theorem."""
    mass = sum(b[0] for b in bodies)
    center = sum(b[0] * b[1] for b in bodies) / mass
    inertia = np.zeros((3, 3))
    for m, c, i in bodies:
        d = c - center
        inertia += i + m * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return mass, center, inertia


def box(size, density):
    a, b, c = size
    m = density * a * b * c
    return m, np.zeros(3), m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])


def sphere(r, density):
    m = density * 4 / 3 * np.pi * r ** 3
    return m, np.zeros(3), 0.4 * m * r * r * np.eye(3)


def cylinder(r, length, density):
    m = density * np.pi * r * r * length
    side = m * (3 * r * r + length * length) / 12
    return m, np.zeros(3), np.diag([side, side, 0.5 * m * r * r])


def mirrored_wedge():
    """The wedge in metres mirrored in y: y negated and every face's winding reversed, by hand."""
    v = WEDGE_MM * 0.001 * np.array([1.0, -1.0, 1.0])
    return v, WEDGE_FACES[:, ::-1]


def base_link(density=DENSITY):
    return placed(cylinder(0.08, 0.1, density), np.eye(3), np.array([0, 0, 0.05]))


def upper_link(density=DENSITY, knob="sphere"):
    """The URDF/SDF upper link (knob: the sphere) or the MJCF one (knob: the capsule)."""
    box_part = placed(box(np.array(BOX_MM) * 0.001, density), rz(YAW_BOX), np.array([0, 0, 0.1]))
    # The box mesh spans z 0..200 mm: its centre is at 0.1 m in its own frame.
    box_part = (box_part[0], box_part[1] + rz(YAW_BOX) @ np.array([0, 0, 0.1]), box_part[2])
    wedge = placed(mesh_body(*mirrored_wedge(), density), rpy(*RPY_WEDGE), np.array([0.02, 0, 0]))
    if knob == "sphere":
        end = placed(sphere(0.03, density), np.eye(3), np.array([0, 0, 0.4]))
    else:
        end = capsule_between(np.array([0, 0, 0.4]), np.array([0.1, 0.05, 0.45]), 0.02, density)
    return combined([box_part, wedge, end])


def capsule_between(a, b, r, density):
    """A capsule of radius r around the segment a-b: a cylinder and two half balls (closed
    forms: each hemisphere's centre is 3r/8 from its flat face)."""
    axis = b - a
    length = np.linalg.norm(axis)
    k = axis / length
    cyl_m = density * np.pi * r * r * length
    ball_m = density * 4 / 3 * np.pi * r ** 3
    # Inertia about the capsule's centre, axis z: cylinder plus the two hemispheres moved.
    half = length / 2
    cyl_side = cyl_m * (3 * r * r + length * length) / 12
    hemi_m = ball_m / 2
    hemi_side_own = hemi_m * (2 / 5 * r * r) - hemi_m * (3 * r / 8) ** 2  # about its own centre
    dist = half + 3 * r / 8
    side = cyl_side + 2 * (hemi_side_own + hemi_m * dist ** 2)
    axial = cyl_m * r * r / 2 + ball_m * 2 / 5 * r * r
    local = np.diag([side, side, axial])
    z = np.array([0, 0, 1.0])
    v = np.cross(z, k)
    s, c = np.linalg.norm(v), np.dot(z, k)
    vx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    rot = np.eye(3) + vx + vx @ vx * ((1 - c) / s ** 2)
    return cyl_m + ball_m, (a + b) / 2, rot @ local @ rot.T
