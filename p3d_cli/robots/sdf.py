"""SDFormat (Gazebo): links, their collision and visual geometry, and declared inertials.

Conventions (http://sdformat.org/spec): a ``<pose>`` is ``x y z roll pitch yaw`` (radians; the
same fixed-axis ``R = Rz Ry Rx`` as URDF; ``degrees="true"`` and SDF 1.9's
``rotation_format="quat_xyzw"`` are read too); a collision's, visual's and inertial's pose is in
its link's frame (a ``relative_to`` naming another frame is refused rather than guessed); the
inertia is about the centre of mass in the inertial pose's frame; ``box size`` is the full size,
``cylinder`` and ``capsule`` have their axis along z and ``length`` the full length of the
cylindrical part; ``model://NAME/...`` URIs are found through the package paths, then the folders
of ``GZ_SIM_RESOURCE_PATH`` (and its older names). Nested models' links are named
``model::link``.
"""

from __future__ import annotations

import math
import os

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.placement import Placement
from p3d_cli.robots.model import Geom, Link, Robot, inertia_matrix, resolve_uri, rotated_inertial, spec
from p3d_cli.robots.xmltree import Node, numbers


def pose(node: Node | None, where: str, link: str) -> tuple[np.ndarray, np.ndarray | None]:
    """The translation and rotation of a ``<pose>`` element (None: identity)."""
    from p3d_cli.rotation import rotation_from_quaternion, rotation_from_rpy

    if node is None or not node.text:
        return np.zeros(3), None
    relative = node.attrib.get("relative_to")
    if relative not in (None, "", link):
        raise InputError(where, f"pose relative_to={relative!r} is not read (only poses in the link frame)",
                         "give the pose in the link's frame")
    if node.attrib.get("rotation_format") == "quat_xyzw":
        x, y, z, qx, qy, qz, qw = numbers(node.text, 7, f"{where}: pose")
        try:
            return np.array([x, y, z]), rotation_from_quaternion(qw, qx, qy, qz)
        except UsageError as exc:
            raise InputError(f"{where}: pose", exc.what, "give a non-zero quaternion x y z w") from None
    values = numbers(node.text, 6, f"{where}: pose")
    if node.attrib.get("degrees", "false").lower() == "true":
        values[3:] = [math.radians(v) for v in values[3:]]
    rotation = rotation_from_rpy(*values[3:]) if any(values[3:]) else None
    return np.array(values[:3]), rotation


def read_sdf(path: str, data: bytes, root: Node, packages: dict[str, str]) -> Robot:
    """The links of every model of an SDF document.

    Raises
    ------
    InputError
        Not ``<sdf>``, a link without a name, a bad number or geometry, a missing mesh.
    """
    if root.tag != "sdf":
        raise InputError(path, f"the root element is <{root.tag}>, not <sdf>", "give an SDF file")
    links: list[Link] = []
    for model in [m for m in root.children if m.tag == "model"] + [m for w in root.findall("world")
                                                                    for m in w.findall("model")]:
        _model(path, model, "", packages, links)
    return Robot(path, "sdf", data, links)


def _model(path: str, model: Node, prefix: str, packages: dict[str, str], links: list[Link]) -> None:
    base = os.path.dirname(path)
    for node in model.children:
        if node.tag == "model":
            _model(path, node, f"{prefix}{node.attrib.get('name', '')}::", packages, links)
        if node.tag == "include":
            raise InputError(f"{path}: line {node.line}", "<include> is not read",
                             "give the model with its includes expanded (gz sdf -p model.sdf)")
        if node.tag != "link":
            continue
        name = node.attrib.get("name")
        if not name:
            raise InputError(f"{path}: line {node.line}", "a <link> has no name", "name every link")
        where = f"{path}: link {prefix + name!r}"
        link = Link(prefix + name, node)
        for role in ("collision", "visual"):
            for i, element in enumerate(node.findall(role)):
                label = element.attrib.get("name")
                geom = _geometry(element, f"{where}: {role} {label!r}" if label else f"{where}: {role}[{i}]",
                                 base, packages, role, name)
                if geom is not None:
                    link.geoms(role).append(geom)
        inertial = node.find("inertial")
        if inertial is not None:
            link.inertial_node = inertial
            link.inertial = _inertial(inertial, f"{where}: inertial", name)
        links.append(link)


def _inertial(node: Node, where: str, link: str):
    mass = numbers(node.child_text("mass"), 1, f"{where}: mass", [1.0])  # SDF's default mass is 1
    center, rotation = pose(node.find("pose"), where, link)
    tensor = node.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    defaults = {"ixx": 1.0, "iyy": 1.0, "izz": 1.0}  # SDF's defaults: the unit tensor
    values = [numbers(None if tensor is None else tensor.child_text(k), 1, f"{where}: inertia {k}",
                      [defaults.get(k, 0.0)])[0] for k in keys]
    return rotated_inertial(mass[0], center, rotation, inertia_matrix(*values))


def _geometry(element: Node, where: str, base: str, packages: dict[str, str], role: str, link: str) -> Geom | None:
    geometry = element.find("geometry")
    if geometry is None or not geometry.children:
        return None
    shape = geometry.children[0]
    kind = shape.tag
    scale = None

    def one(key: str) -> float:
        value = numbers(shape.child_text(key), 1, f"{where}: {kind} {key}")
        if value is None or value[0] <= 0:
            raise InputError(where, f"<{kind}> needs a positive <{key}>", f"give the {key}")
        return value[0]

    if kind == "mesh":
        uri = shape.child_text("uri")
        if not uri:
            raise InputError(where, "a <mesh> has no <uri>", "give the mesh's path or model:// URI")
        thing = resolve_uri(uri, base, packages, where)
        s = numbers(shape.child_text("scale"), 3, f"{where}: mesh scale")
        scale = None if s is None or all(v == 1 for v in s) else np.array(s)
    elif kind in ("box", "ellipsoid"):
        key = "size" if kind == "box" else "radii"
        values = numbers(shape.child_text(key), 3, f"{where}: {kind} {key}")
        if values is None or any(v <= 0 for v in values):
            raise InputError(where, f"<{kind}> needs three positive numbers in <{key}>", f"give the {key}")
        thing = spec(kind, *(0.5 * v if kind == "box" else v for v in values))
    elif kind == "cylinder":
        r = one("radius")
        thing = spec("cylinder", r, r, 0.5 * one("length"))
    elif kind == "capsule":
        thing = spec("capsule", one("radius"), 0.5 * one("length"))
    elif kind == "sphere":
        thing = spec("sphere", one("radius"))
    elif kind in ("plane", "heightmap", "empty"):
        return None
    else:
        raise InputError(where, f"<{kind}> is not a geometry p3d reads", "use mesh, box, cylinder, sphere, capsule")
    translation, rotation = pose(element.find("pose"), where, link)
    return Geom(thing, Placement(scale, rotation, translation if np.any(translation) else None), where, role)
