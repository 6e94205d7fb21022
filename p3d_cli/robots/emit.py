"""``<inertial>`` elements as URDF, MJCF and SDF write them, from a mass, centre and tensor.

Every block is in the link (body) frame: the centre of mass as the inertial's origin, with no
rotation, and the full tensor about the centre of mass along the link frame's axes (positive
convention, ``Ixx = ∫(y²+z²) dm``, ``Ixy = -∫xy dm``). Numbers are written with ``repr`` (the
shortest text that reads back as the same float64), so a filled file loses no precision.
"""

from __future__ import annotations

import numpy as np

#: The formats ``inertial_block`` writes.
EMIT_FORMATS = ("urdf", "mjcf", "sdf")

#: The frame convention every block states.
CONVENTION = ("origin at the centre of mass, axes of the link frame (the mesh's frame after any placement "
              "given; no rotation); inertia about the centre of mass, positive tensor "
              "(Ixx = integral of (y^2+z^2) dm, Ixy = -integral of xy dm)")


def fmt(*values: float) -> str:
    """Numbers as shortest round-trip text, space-separated (``-0.0`` written as ``0.0``)."""
    return " ".join(repr(float(v) + 0.0) for v in values)


def inertial_lines(format: str, mass: float, center, inertia, principal: bool = False) -> list[str]:
    """The lines of one ``<inertial>`` element (without indentation of the whole).

    Parameters
    ----------
    format : {"urdf", "mjcf", "sdf"}
    mass : float
    center : (3,) array_like
        Centre of mass in the link frame.
    inertia : (3, 3) array_like
        About the centre of mass, link-frame axes.
    principal : bool
        MJCF only: write ``quat`` and ``diaginertia`` (the principal frame, as MuJoCo stores it)
        instead of ``fullinertia``.
    """
    c = np.asarray(center, dtype=np.float64)
    i = np.asarray(inertia, dtype=np.float64)
    i = 0.5 * (i + i.T)  # written from one triangle: make sure it is the symmetric part
    six = {"ixx": i[0, 0], "ixy": i[0, 1], "ixz": i[0, 2], "iyy": i[1, 1], "iyz": i[1, 2], "izz": i[2, 2]}
    if format == "urdf":
        return ["<inertial>", f'  <origin xyz="{fmt(*c)}" rpy="0 0 0"/>', f'  <mass value="{fmt(mass)}"/>',
                "  <inertia " + " ".join(f'{k}="{fmt(v)}"' for k, v in six.items()) + "/>", "</inertial>"]
    if format == "mjcf" and principal:
        from p3d_cli.geometry.inertia import principal_frame
        from p3d_cli.geometry.rotation import matrix_quaternion

        moments, axes = principal_frame(i)
        # Rows of ``axes`` are the principal axes in the link frame, so R = axesᵀ takes the
        # principal frame to the link frame: I = R diag(moments) Rᵀ.
        quat = matrix_quaternion(axes.T)
        return [f'<inertial pos="{fmt(*c)}" quat="{fmt(*quat)}" mass="{fmt(mass)}" diaginertia="{fmt(*moments)}"/>']
    if format == "mjcf":
        full = (i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
        return [f'<inertial pos="{fmt(*c)}" mass="{fmt(mass)}" fullinertia="{fmt(*full)}"/>']
    if format == "sdf":
        return ["<inertial>", f"  <pose>{fmt(*c)} 0 0 0</pose>", f"  <mass>{fmt(mass)}</mass>", "  <inertia>",
                *(f"    <{k}>{fmt(v)}</{k}>" for k, v in six.items()), "  </inertia>", "</inertial>"]
    raise ValueError(f"unknown format {format!r}")


def inertial_block(format: str, mass: float, center, inertia, *, source: str = "", units: str = "SI") -> str:
    """A ready ``<inertial>`` element with a comment stating its frame convention and units."""
    comment = f"<!-- p3d: inertial{' of ' + source if source else ''}; {units}; {CONVENTION} -->"
    return "\n".join([comment, *inertial_lines(format, mass, center, inertia)])


def emit_result(format: str, result) -> str:
    """The ``<inertial>`` block of a ``PropsResult`` (a mesh, shape or assembly).

    Without units (``result.units`` says the mesh's own), the numbers are SI only if the mesh is
    in metres and the density in kg/m³; the comment says so.
    """
    p = result.properties
    system = (result.units or {}).get("system")
    if system == "mesh":
        units = "units as given: SI only if the mesh is in metres and the density in kg/m^3 (else give units)"
    elif system == "SI":
        units = "SI (kg, m, kg*m^2)"
    else:
        u = result.units
        units = f"units {u['mass']}, {u['length']}, {u['inertia']} (not SI: output units were asked for)"
    if p.center_of_mass is None:
        from p3d_cli.errors import InputError

        raise InputError(result.facts.source, "encloses no volume, so has no inertial", "give a closed solid")
    return inertial_block(format, p.mass, p.center_of_mass, p.inertia, source=result.facts.source, units=units)
