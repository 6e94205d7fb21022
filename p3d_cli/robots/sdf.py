"""SDFormat (Gazebo): links, their collision and visual geometry, and declared inertials.

Conventions (http://sdformat.org/spec): a ``<pose>`` is ``x y z roll pitch yaw`` (radians; the
same fixed-axis ``R = Rz Ry Rx`` as URDF; ``degrees="true"`` and SDF 1.9's
``rotation_format="quat_xyzw"`` are read too); a collision's, visual's and inertial's pose is in
its link's frame unless its ``relative_to`` names another frame of the model (a link, joint,
``<frame>`` or ``__model__``), which is resolved through the model's frames as libsdformat
resolves them (a link's pose defaults to the model frame, a joint's to its child link, a
frame's to what it is attached to); the inertia is about the centre of mass in the inertial
pose's frame; ``box size`` is the full size,
``cylinder`` and ``capsule`` have their axis along z and ``length`` the full length of the
cylindrical part; ``model://NAME/...`` URIs are found through the package paths, then the folders
of ``GZ_SIM_RESOURCE_PATH`` (and its older names). Nested models' links are named
``model::link``. An ``<include>`` reads the model its ``<uri>`` names (the file its
``model.config`` gives, else ``model.sdf``); its links are named ``name::link``, or keep
their names with ``merge="true"``. At most ``MAX_INCLUDE_DEPTH`` levels of includes.
"""

from __future__ import annotations

import math
import os

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.robots.model import Geom, Link, Robot, inertia_matrix, resolve_uri, rotated_inertial, spec
from p3d_cli.robots.xmltree import Node, numbers
from p3d_cli.shapes import Box, Capsule, Cylinder, Ellipsoid, Sphere


#: Includes inside included models, at most.
MAX_INCLUDE_DEPTH = 16


def pose(node: Node | None, where: str) -> tuple[np.ndarray, np.ndarray | None]:
    """The translation and rotation of a ``<pose>`` element (None: identity)."""
    from p3d_cli.geometry.rotation import rotation_from_quaternion, rotation_from_rpy

    if node is None or not node.text:
        return np.zeros(3), None
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


def _matrix(node: Node | None, where: str) -> np.ndarray:
    """A ``<pose>`` as a 4x4 homogeneous transform."""
    t, r = pose(node, where)
    out = np.eye(4)
    out[:3, :3] = np.eye(3) if r is None else r
    out[:3, 3] = t
    return out


class _Frames:
    """A model's named frames (links, joints, ``<frame>``s, ``__model__``) in the model frame."""

    def __init__(self, path: str, model: Node) -> None:
        self.path = path
        self.declared: dict[str, tuple[Node | None, str]] = {}
        for node in model.children:
            name = node.attrib.get("name")
            if not name or node.tag not in ("link", "joint", "frame", "model"):
                continue
            default = "__model__"
            if node.tag == "joint":
                default = node.child_text("child") or "__model__"
            elif node.tag == "frame":
                default = node.attrib.get("attached_to") or "__model__"
            # A joint and a link may share a name (libsdformat warns): the link's frame wins.
            if name not in self.declared or node.tag == "link":
                self.declared[name] = (node.find("pose"), default)
        self.known: dict[str, np.ndarray] = {"__model__": np.eye(4)}

    def in_model(self, name: str, where: str) -> np.ndarray:
        """``X_model_frame`` of the frame ``name``, following ``relative_to`` chains (a loop, not
        recursion; a cycle or an unknown name is refused)."""
        chain: list[str] = []
        current = name
        while current not in self.known:
            if current in chain:
                raise InputError(where, f"the frames {' -> '.join(chain + [current])} form a cycle",
                                 "fix the relative_to attributes")
            if current not in self.declared:
                raise InputError(where, f"relative_to names {current!r}, which is no frame of this model",
                                 "name a link, joint or frame of the same model, or __model__")
            chain.append(current)
            node, default = self.declared[current]
            current = (node.attrib.get("relative_to") if node is not None else None) or default
        for frame in reversed(chain):
            node, default = self.declared[frame]
            parent = (node.attrib.get("relative_to") if node is not None else None) or default
            self.known[frame] = self.known[parent] @ _matrix(node, f"{where}: frame {frame!r}")
        return self.known[name]

    def in_link(self, node: Node | None, link: str, where: str) -> tuple[np.ndarray, np.ndarray | None]:
        """The translation and rotation of an element's ``<pose>`` in its link's frame."""
        relative = None if node is None else node.attrib.get("relative_to")
        if relative in (None, "", link):
            return pose(node, where)
        x = np.linalg.solve(self.in_model(link, where), self.in_model(relative, where)) @ _matrix(node, where)
        rotation = x[:3, :3]
        return x[:3, 3], None if np.allclose(rotation, np.eye(3), rtol=0, atol=1e-15) else rotation


def read_sdf(path: str, root: Node, packages: dict[str, str]) -> Robot:
    """The links of every model of an SDF document, with the models it includes.

    Raises
    ------
    InputError
        Not ``<sdf>``, a link without a name, a bad number or geometry, a missing mesh or
        included model, a frame that does not resolve.
    """
    if root.tag != "sdf":
        raise InputError(path, f"the root element is <{root.tag}>, not <sdf>", "give an SDF file")
    links: list[Link] = []
    holders = [root] + root.findall("world")
    stack = [(path, m, "", 0) for holder in reversed(holders) for m in reversed(holder.children)
             if m.tag in ("model", "include")]
    while stack:
        source, node, prefix, depth = stack.pop()
        if node.tag == "include":
            model, merged = _include(source, node, packages, depth)
            name = node.child_text("name") or model.attrib.get("name", "")
            node, prefix = model, prefix if merged else f"{prefix}{name}::"
            source, depth = model.doc.path, depth + 1
        nested = _model(source, node, prefix, packages, links)
        stack.extend((source, child, f"{prefix}{child.attrib.get('name', '')}::" if child.tag == "model"
                      else prefix, depth) for child in reversed(nested))
    return Robot(path, "sdf", root.doc, links)


def _include(source: str, node: Node, packages: dict[str, str], depth: int) -> tuple[Node, bool]:
    """The ``<model>`` an ``<include>`` names, and whether it is merged into the including one."""
    from p3d_cli.robots.xmltree import read_xml

    where = f"{node.where}: <include>"
    if depth >= MAX_INCLUDE_DEPTH:
        raise InputError(where, f"includes nest deeper than {MAX_INCLUDE_DEPTH} levels", "is the model looping?")
    uri = node.child_text("uri")
    if not uri:
        raise InputError(where, "has no <uri>", "give the model's model:// URI or folder")
    folder = resolve_uri(uri, os.path.dirname(source), packages, where, folder=True)
    file = folder
    if os.path.isdir(folder):
        file = os.path.join(folder, "model.sdf")
        config = os.path.join(folder, "model.config")
        if os.path.isfile(config):
            named = read_xml(config, where).child_text("sdf")
            if named:
                file = os.path.join(folder, named)
    root = read_xml(file, where)
    model = root.find("model") if root.tag == "sdf" else None
    if model is None:
        raise InputError(f"{file}: line {root.line}", "holds no <sdf><model>", "include a model")
    return model, node.attrib.get("merge", "false").lower() == "true"


def _model(path: str, model: Node, prefix: str, packages: dict[str, str], links: list[Link]) -> list[Node]:
    """The model's links (appended to ``links``); returns its nested models and includes."""
    base = os.path.dirname(path)
    frames = _Frames(path, model)
    nested = []
    for node in model.children:
        if node.tag in ("model", "include"):
            nested.append(node)
        if node.tag != "link":
            continue
        name = node.attrib.get("name")
        if not name:
            raise InputError(f"{path}: line {node.line}", "a <link> has no name", "name every link")
        where = f"{node.doc.path if node.doc else path}:{node.line}: link {prefix + name!r}"
        link = Link(prefix + name, node)
        for role in ("collision", "visual"):
            for i, element in enumerate(node.findall(role)):
                label = element.attrib.get("name")
                geom = _geometry(element, f"{where}: {role} {label!r}" if label else f"{where}: {role}[{i}]",
                                 base, packages, role, name, frames)
                if geom is not None:
                    link.geoms(role).append(geom)
        inertial = node.find("inertial")
        if inertial is not None:
            link.inertial_node = inertial
            link.inertial = _inertial(inertial, f"{where}: inertial", name, frames)
        links.append(link)
    return nested


def _inertial(node: Node, where: str, link: str, frames: _Frames):
    mass = numbers(node.child_text("mass"), 1, f"{where}: mass", [1.0])  # SDF's default mass is 1
    center, rotation = frames.in_link(node.find("pose"), link, where)
    tensor = node.find("inertia")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    defaults = {"ixx": 1.0, "iyy": 1.0, "izz": 1.0}  # SDF's defaults: the unit tensor
    values = [numbers(None if tensor is None else tensor.child_text(k), 1, f"{where}: inertia {k}",
                      [defaults.get(k, 0.0)])[0] for k in keys]
    return rotated_inertial(mass[0], center, rotation, inertia_matrix(*values))


def _geometry(element: Node, where: str, base: str, packages: dict[str, str], role: str, link: str,
              frames: _Frames) -> Geom | None:
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
        thing = spec(Box(*(0.5 * v for v in values)) if kind == "box" else Ellipsoid(*values))
    elif kind == "cylinder":
        r = one("radius")
        thing = spec(Cylinder(r, 0.5 * one("length")))
    elif kind == "capsule":
        thing = spec(Capsule(one("radius"), 0.5 * one("length")))
    elif kind == "sphere":
        thing = spec(Sphere(one("radius")))
    elif kind in ("plane", "heightmap", "empty"):
        return None
    else:
        raise InputError(where, f"<{kind}> is not a geometry p3d reads", "use mesh, box, cylinder, sphere, capsule")
    translation, rotation = frames.in_link(element.find("pose"), link, where)
    return Geom(thing, Placement(scale, rotation, translation if np.any(translation) else None), where, role)
