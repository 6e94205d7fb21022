"""URDF: links, their visual and collision geometry, and declared inertials.

Conventions (https://wiki.ros.org/urdf/XML/link): ``<origin xyz rpy>`` places an element in its
link's frame, rpy being turns about the fixed x, y, z axes (``R = Rz Ry Rx``,
``p3d_cli.geometry.rotation.rotation_from_rpy``); the ``<inertia>`` tensor is about the centre of mass,
in the frame of the inertial's origin (so rotated by its rpy); ``box size`` is the full size,
``cylinder`` has its axis along z with ``length`` the full length; a mesh's ``scale`` applies
in the mesh's own frame, before the origin. The file is read with the standard library's expat
(``p3d_cli.robots.xmltree``); xacro files are expanded first (``p3d_cli.robots.xacro``).
"""

from __future__ import annotations

import os

import numpy as np

from p3d_cli.errors import InputError
from p3d_cli.geometry.placement import Placement
from p3d_cli.robots.model import Geom, Link, Robot, inertia_matrix, resolve_uri, rotated_inertial, spec
from p3d_cli.robots.xmltree import Node, numbers
from p3d_cli.shapes import Box, Capsule, Cylinder, Sphere


def origin_placement(node: Node | None, where: str, scale=None) -> Placement:
    """The placement of an ``<origin xyz rpy>`` element (None: identity), after ``scale``."""
    from p3d_cli.geometry.rotation import rotation_from_rpy

    xyz = rpy = None
    if node is not None:
        xyz = numbers(node.attrib.get("xyz"), 3, f"{where}: origin xyz")
        rpy = numbers(node.attrib.get("rpy"), 3, f"{where}: origin rpy")
    rotation = None if rpy is None or not any(rpy) else rotation_from_rpy(*rpy)
    translation = None if xyz is None or not any(xyz) else np.array(xyz)
    return Placement(scale, rotation, translation)


def read_urdf(path: str, root: Node, packages: dict[str, str]) -> Robot:
    """The links of a URDF document: the ``<link>`` children of ``<robot>`` (a ``<link>`` inside
    a ``<gazebo>``, ``<transmission>`` or other extension block is not a robot link).

    Raises
    ------
    InputError
        Not a ``<robot>``, a link without a name, a bad number or geometry, a missing mesh.
    """
    if root.tag != "robot":
        raise InputError(path, f"the root element is <{root.tag}>, not <robot>", "give a URDF file")
    base = os.path.dirname(path)
    links = []
    for node in root.findall("link"):
        name = node.attrib.get("name")
        if not name:
            raise InputError(f"{path}: line {node.line}", "a <link> has no name", "name every link")
        where = f"{path}:{node.line}: link {name!r}"
        link = Link(name, node)
        for role in ("collision", "visual"):
            for i, element in enumerate(node.findall(role)):
                geom = _geometry(element, f"{where}: {role}[{i}]", base, packages, role)
                if geom is not None:
                    link.geoms(role).append(geom)
        inertial = node.find("inertial")
        if inertial is not None:
            link.inertial_node = inertial
            link.inertial = _inertial(inertial, f"{where}: inertial")
        links.append(link)
    return Robot(path, "urdf", root.doc, links)


def _inertial(node: Node, where: str):
    from p3d_cli.geometry.rotation import rotation_from_rpy

    mass_node = node.find("mass")
    mass = numbers(None if mass_node is None else mass_node.attrib.get("value"), 1, f"{where}: mass value")
    if mass is None:
        raise InputError(where, "has no <mass value=...>", "give the link's mass in kg")
    tensor = node.find("inertia")
    if tensor is None:
        raise InputError(where, "has no <inertia>", "give ixx, ixy, ixz, iyy, iyz, izz")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    values = [numbers(tensor.attrib.get(k), 1, f"{where}: inertia {k}", [0.0])[0] for k in keys]
    origin = node.find("origin")
    xyz = rpy = None
    if origin is not None:
        xyz = numbers(origin.attrib.get("xyz"), 3, f"{where}: origin xyz")
        rpy = numbers(origin.attrib.get("rpy"), 3, f"{where}: origin rpy")
    rotation = None if rpy is None else rotation_from_rpy(*rpy)
    return rotated_inertial(mass[0], xyz or [0.0, 0.0, 0.0], rotation, inertia_matrix(*values))


def _geometry(element: Node, where: str, base: str, packages: dict[str, str], role: str) -> Geom | None:
    """One ``<collision>`` or ``<visual>`` as a ``Geom`` (None: it has no geometry)."""
    geometry = element.find("geometry")
    if geometry is None or not geometry.children:
        return None
    shape = geometry.children[0]
    kind, a = shape.tag, shape.attrib
    scale = None
    if kind == "mesh":
        filename = a.get("filename")
        if not filename:
            raise InputError(where, "a <mesh> has no filename", "give the mesh's path or package:// URI")
        thing = resolve_uri(filename, base, packages, where)
        s = numbers(a.get("scale"), (1, 3), f"{where}: mesh scale")
        scale = None if s is None or all(v == 1 for v in s) else np.array(s * 3 if len(s) == 1 else s)
    elif kind == "box":
        size = numbers(a.get("size"), 3, f"{where}: box size")
        thing = spec(Box(*(0.5 * v for v in _required(size, where, "box size"))))
    elif kind == "cylinder":
        r = _one(a, "radius", where)
        thing = spec(Cylinder(r, 0.5 * _one(a, "length", where)))
    elif kind == "capsule":  # not in the URDF standard, but read by several tools
        thing = spec(Capsule(_one(a, "radius", where), 0.5 * _one(a, "length", where)))
    elif kind == "sphere":
        thing = spec(Sphere(_one(a, "radius", where)))
    else:
        raise InputError(where, f"<{kind}> is not a URDF geometry", "use mesh, box, cylinder or sphere")
    return Geom(thing, origin_placement(element.find("origin"), where, scale), where, role)


def _one(attrib: dict, key: str, where: str) -> float:
    value = numbers(attrib.get(key), 1, f"{where}: {key}")
    return _required(value, where, key)[0]


def _required(values, where: str, key: str) -> list[float]:
    if values is None:
        raise InputError(where, f"has no {key}", f"give {key}")
    if any(v <= 0 for v in values):
        raise InputError(where, f"{key} {' '.join(map(repr, values))} is not positive", f"give a positive {key}")
    return values
