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


def load_robot(path, package_paths=None) -> Robot:
    """Read a robot description: its links, geometry (mesh files resolved) and inertials.

    Parameters
    ----------
    path : str or os.PathLike
        A URDF, MJCF or SDF file (xacro files must be expanded first).
    package_paths : dict or list of "NAME=DIR", optional
        Folders of the packages ``package://NAME/...`` (``model://NAME/...``) URIs name; then
        the folders of ``ROS_PACKAGE_PATH`` (``GZ_SIM_RESOURCE_PATH``) are searched.

    Raises
    ------
    InputError, FormatError
        Unreadable, not XML, not a robot description, a xacro file, a bad element, a missing
        mesh (named by file, link and element).
    """
    from p3d_cli.robots.xmltree import read_xml

    path = os.fspath(path)
    packages = parse_package_paths(package_paths)
    if path.endswith(".xacro"):
        raise InputError(path, "is a xacro file, which p3d does not expand",
                         "expand it first: xacro robot.urdf.xacro > robot.urdf")
    data, root = read_xml(path)
    if b"xmlns:xacro" in data[:4096] or any(node.tag.startswith("xacro:") for node in root.iter()):
        raise InputError(path, "uses xacro macros, which p3d does not expand",
                         "expand it first: xacro robot.urdf.xacro > robot.urdf")
    kind = detect_format(path, root.tag)
    if kind == "urdf":
        from p3d_cli.robots.urdf import read_urdf as read
    elif kind == "mjcf":
        from p3d_cli.robots.mjcf import read_mjcf as read
    else:
        from p3d_cli.robots.sdf import read_sdf as read
    return read(path, data, root, packages)
