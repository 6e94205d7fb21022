"""Robot descriptions (URDF, MJCF, SDF): read their links, check and fill their inertials.

>>> from p3d_cli.robots import load_robot, check_robot, fill_robot   # doctest: +SKIP
>>> robot = load_robot("arm.urdf", package_paths={"arm_description": "./arm"})
>>> [c.link for c in check_robot(robot) if not c.ok]

A link is an assembly of its geoms (``p3d_cli.robots.geometry``); the formats are read by one
module each (``urdf``, ``mjcf``, ``sdf``) into the types of ``p3d_cli.robots.model``.
"""

from __future__ import annotations

import os

from p3d_cli.errors import InputError
from p3d_cli.robots.check import LinkCheck, Problem, check_robot
from p3d_cli.robots.fill import FillResult, fill_robot, load_masses
from p3d_cli.robots.model import Robot, parse_package_paths

__all__ = ["load_robot", "check_robot", "fill_robot", "load_masses", "Robot", "LinkCheck", "Problem",
           "FillResult", "detect_format"]

#: Root element -> format.
ROOTS = {"robot": "urdf", "mujoco": "mjcf", "sdf": "sdf"}


def detect_format(path: str, root_tag: str) -> str:
    """The description's format, from its root element."""
    if root_tag in ROOTS:
        return ROOTS[root_tag]
    raise InputError(path, f"the root element <{root_tag}> is none of <robot> (URDF), <mujoco> (MJCF), "
                     "<sdf> (SDF)", "give a URDF, MJCF or SDF file")


def load_robot(path, package_paths=None, xacro_args=None) -> Robot:
    """Read a robot description: its links, geometry (mesh files resolved) and inertials.

    Parameters
    ----------
    path : str or os.PathLike
        A URDF, MJCF or SDF file, or a xacro file (expanded with the ``xacro`` package: the
        ``robots`` extra).
    package_paths : dict or list of "NAME=DIR", optional
        Folders of the packages ``package://NAME/...`` (``model://NAME/...``) URIs name, and
        xacro's ``$(find NAME)``; then the folders of ``ROS_PACKAGE_PATH``
        (``GZ_SIM_RESOURCE_PATH``) are searched, then the folders above the description
        (``p3d_cli.robots.model.nearby_packages``).
    xacro_args : dict or list of "NAME:=VALUE", optional
        Arguments of a xacro file (``xacro:arg``).

    Raises
    ------
    InputError, FormatError
        Unreadable, not XML, not a robot description, a bad element, a missing mesh (named by
        file, link and element).
    MissingExtraError
        A xacro file without the ``xacro`` package installed.
    """
    from p3d_cli.robots.xmltree import read_xml

    path = os.fspath(path)
    packages = parse_package_paths(package_paths)
    root = read_xml(path)
    if path.endswith(".xacro") or _uses_xacro(root):
        from p3d_cli.robots.xacro import expand_xacro

        root = expand_xacro(path, root, packages, xacro_args)
    kind = detect_format(path, root.tag)
    if kind == "urdf":
        from p3d_cli.robots.urdf import read_urdf as read
    elif kind == "mjcf":
        from p3d_cli.robots.mjcf import read_mjcf as read
    else:
        from p3d_cli.robots.sdf import read_sdf as read
    return read(path, root, packages)


def _uses_xacro(root) -> bool:
    """Whether a document holds xacro elements. A declaration of the namespace alone does not
    count: xacro's own output keeps ``xmlns:xacro`` on ``<robot>``."""
    return any(node.tag.startswith("xacro:") for node in root.iter())
