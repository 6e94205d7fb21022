"""A constraint's geometry in the world frame at one instant.

Every constraint type works from the same few world-frame quantities: the offsets ``r`` of its
attachment points from each body's centre of mass (docs/method.md, "Frames": ``r = attachment - centre of
mass``, rotated into the world), the attachment points themselves, and the body-frame vectors the
type declares in its ``TURNED`` (a hinge's axes), turned into the world.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from p3d_cli.constraints.registry import CONSTRAINT_TYPES


@dataclass(frozen=True)
class JointGeometry:
    """World-frame geometry of one constraint.

    Attributes
    ----------
    r_a, r_b : (3,) float64
        Attachment point minus centre of mass, world frame.
    p_a, p_b : (3,) float64
        Attachment points, world frame.
    turned : tuple of (3,) float64
        The type's ``TURNED`` vectors in the world frame, in its order (a hinge's ``(z_a, z_b)``).
    where : str
        The constraint's place in the scene, for messages.
    """

    r_a: np.ndarray
    r_b: np.ndarray
    p_a: np.ndarray
    p_b: np.ndarray
    turned: tuple = ()
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
    turned = tuple((rot_a if side == "a" else rot_b) @ spec.values[name]
                   for name, side in CONSTRAINT_TYPES[spec.type].TURNED)
    return JointGeometry(r_a, r_b, com_a + r_a, com_b + r_b, turned, spec.where)
