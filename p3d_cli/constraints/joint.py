"""A constraint's geometry in the world frame at one instant.

Every constraint type works from the same few world-frame quantities: the offsets ``r`` of its
attachment points from each body's centre of mass (docs/method.md, "Frames": ``r = attachment - centre of
mass``, rotated into the world), the attachment points themselves, and for a hinge its axes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class JointGeometry:
    """World-frame geometry of one constraint.

    Attributes
    ----------
    r_a, r_b : (3,) float64
        Attachment point minus centre of mass, world frame.
    p_a, p_b : (3,) float64
        Attachment points, world frame.
    z_a, z_b : (3,) float64 or None
        Unit hinge axes, world frame.
    where : str
        The constraint's place in the scene, for messages.
    """

    r_a: np.ndarray
    r_b: np.ndarray
    p_a: np.ndarray
    p_b: np.ndarray
    z_a: np.ndarray | None = None
    z_b: np.ndarray | None = None
    where: str = ""


def joint_geometry(spec, com_a, rot_a, com_body_a, com_b, rot_b, com_body_b) -> JointGeometry:
    """World geometry of constraint ``spec`` for bodies at the given poses.

    Parameters
    ----------
    spec : ConstraintSpec
    com_a, com_b : (3,) float64
        World centres of mass.
    rot_a, rot_b : (3, 3) float64
        Body-to-world rotations.
    com_body_a, com_body_b : (3,) float64
        Centres of mass in the body frames.
    """
    r_a = rot_a @ (spec.attach_a - com_body_a)
    r_b = rot_b @ (spec.attach_b - com_body_b)
    z_a = z_b = None
    if spec.axis_a is not None:
        z_a, z_b = rot_a @ spec.axis_a, rot_b @ spec.axis_b
    return JointGeometry(r_a, r_b, com_a + r_a, com_b + r_b, z_a, z_b, spec.where)
