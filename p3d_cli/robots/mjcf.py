"""MJCF (MuJoCo): bodies, their geoms and declared inertials.

Conventions (https://mujoco.readthedocs.io/en/stable/XMLreference.html): a geom's ``pos`` and
orientation (``quat`` w x y z, ``axisangle``, ``euler`` with ``compiler eulerseq``, ``xyaxes``,
``zaxis``, or ``fromto`` for capsules, cylinders, boxes and ellipsoids) place it in its body's
frame; angles are in degrees unless ``<compiler angle="radian">``; ``size`` holds half-sizes
(a capsule's and cylinder's second number is the half-length); a mesh asset's ``scale`` (which
may be negative: a mirror) applies to its vertices, found under ``meshdir`` (else ``assetdir``)
relative to the model file. A mesh geom's vertices sit in the geom frame as in the file
(MuJoCo re-centres the mesh internally and offsets the geom to match). Default classes
(``<default class>``, ``class``, ``childclass``) are resolved as MuJoCo does: nested defaults
inherit, and an element takes its own ``class`` or its nearest enclosing ``childclass``.

Which geoms are a body's collision geometry: those that can collide (``contype`` or
``conaffinity`` non-zero, MuJoCo's default); the others (both zero) are its visual geometry.
"""

from __future__ import annotations

import copy
import math
import os

import numpy as np

from p3d_cli.errors import InputError, UsageError
from p3d_cli.placement import Placement
from p3d_cli.robots.model import Geom, Link, Robot, rotated_inertial, spec
from p3d_cli.robots.xmltree import Node, numbers

_AXES = {"x": np.array([1.0, 0.0, 0.0]), "y": np.array([0.0, 1.0, 0.0]), "z": np.array([0.0, 0.0, 1.0])}


class _Context:
    """What the whole file sets: the compiler's conventions, default classes, mesh assets."""

    def __init__(self, path: str, root: Node) -> None:
        self.path = path
        compiler: dict[str, str] = {}
        for node in root.findall("compiler"):
            compiler.update(node.attrib)
        self.degrees = compiler.get("angle", "degree") != "radian"
        self.eulerseq = compiler.get("eulerseq", "xyz")
        if len(self.eulerseq) != 3 or any(c not in "xyzXYZ" for c in self.eulerseq):
            raise InputError(f"{path}: compiler eulerseq", f"{self.eulerseq!r} is not three of x, y, z, X, Y, Z",
                             "write e.g. xyz (rotating axes) or XYZ (fixed axes)")
        self.from_geoms = compiler.get("inertiafromgeom", "auto") == "true"
        folder = os.path.dirname(path)
        meshdir = compiler.get("meshdir", compiler.get("assetdir", ""))
        self.meshdir = os.path.join(folder, meshdir)
        self.defaults: dict[str, dict[str, dict[str, str]]] = {}
        for node in root.findall("default"):
            self._read_defaults(node, {}, "main")
        self.meshes: dict[str, tuple[str, np.ndarray | None]] = {}
        for asset in root.findall("asset"):
            for mesh in asset.findall("mesh"):
                self._read_mesh(mesh)

    def _read_defaults(self, node: Node, inherited: dict, name: str) -> None:
        name = node.attrib.get("class", name)
        own = copy.deepcopy(inherited)
        for child in node.children:
            if child.tag != "default":
                own.setdefault(child.tag, {}).update(child.attrib)
        self.defaults[name] = own
        for child in node.findall("default"):
            self._read_defaults(child, own, "")

    def attributes(self, node: Node, childclass: str) -> dict[str, str]:
        """``node``'s attributes over those of its default class."""
        name = node.attrib.get("class", childclass)
        if name not in self.defaults and name != "main":
            raise InputError(f"{self.path}: line {node.line}", f"<{node.tag}> names class {name!r}, which is not "
                             "defined", "define it under <default>")
        out = dict(self.defaults.get(name, {}).get(node.tag, {}))
        out.update(node.attrib)
        return out

    def _read_mesh(self, mesh: Node) -> None:
        a = self.attributes(mesh, "main")
        where = f"{self.path}: mesh asset line {mesh.line}"
        file = a.get("file")
        name = a.get("name") or (os.path.splitext(os.path.basename(file))[0] if file else None)
        if not name:
            raise InputError(where, "has neither name nor file", "give the mesh a file")
        if not file:
            self.meshes[name] = ("", None)  # inline or generated: reported when a geom uses it
            return
        # A missing file is reported by the geom that uses it (naming its body), not here.
        path = file if os.path.isabs(file) else os.path.join(self.meshdir, file)
        scale = numbers(a.get("scale"), 3, f"{where}: scale")
        self.meshes[name] = (path, None if scale is None or all(s == 1 for s in scale) else np.array(scale))

    def angle(self, value: float) -> float:
        return math.radians(value) if self.degrees else value

    def rotation(self, a: dict[str, str], where: str) -> np.ndarray | None:
        """The rotation an element's orientation attributes give (None: none given).

        Raises
        ------
        InputError
            A malformed or degenerate orientation (a zero quaternion or axis).
        """
        try:
            with np.errstate(all="ignore"):  # huge axes overflow to inf or nan: refused below
                r = self._rotation(a, where)
        except UsageError as exc:
            raise InputError(f"{where}: {exc.where}", exc.what, "give a valid orientation") from None
        if r is not None and not np.all(np.isfinite(r)):
            raise InputError(where, "the orientation is not finite (an axis too long or zero)",
                             "give a valid orientation")
        return r

    def _rotation(self, a: dict[str, str], where: str) -> np.ndarray | None:
        from p3d_cli.rotation import rotation_from_axis_degrees, rotation_from_quaternion

        if "quat" in a:
            # MuJoCo normalises quaternions; so does rotation_from_quaternion.
            return rotation_from_quaternion(*numbers(a["quat"], 4, f"{where}: quat"))
        if "axisangle" in a:
            x, y, z, t = numbers(a["axisangle"], 4, f"{where}: axisangle")
            return rotation_from_axis_degrees((x, y, z), math.degrees(self.angle(t)))
        if "euler" in a:
            angles = numbers(a["euler"], 3, f"{where}: euler")
            r = np.eye(3)
            for axis, value in zip(self.eulerseq, angles):
                turn = rotation_from_axis_degrees(_AXES[axis.lower()], math.degrees(self.angle(value)))
                # Lower case: about the turning (body) axes, so later turns apply on the right;
                # upper case: about the fixed axes, on the left (MuJoCo's eulerseq).
                r = r @ turn if axis.islower() else turn @ r
            return r
        if "xyaxes" in a:
            v = np.array(numbers(a["xyaxes"], 6, f"{where}: xyaxes"))
            x = v[:3] / np.linalg.norm(v[:3])
            y = v[3:] - np.dot(v[3:], x) * x
            if not np.all(np.isfinite(x)) or not np.linalg.norm(y) > 0:
                raise UsageError("xyaxes", f"{a['xyaxes']!r} are not two independent axes", "")
            y /= np.linalg.norm(y)
            return np.column_stack([x, y, np.cross(x, y)])
        if "zaxis" in a:
            return z_to(np.array(numbers(a["zaxis"], 3, f"{where}: zaxis")))
        return None


def z_to(direction: np.ndarray) -> np.ndarray:
    """The shortest turn taking +z to ``direction`` (MuJoCo's ``mju_quatZ2Vec``)."""
    from p3d_cli.rotation import rotation_from_axis_degrees

    length = math.hypot(*direction)
    if not 0 < length < math.inf:
        raise UsageError("zaxis", "is zero or not finite", "")
    d = direction / length
    axis = np.cross([0.0, 0.0, 1.0], d)
    s = np.linalg.norm(axis)
    if s < 1e-15:
        return np.eye(3) if d[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return rotation_from_axis_degrees(axis / s, math.degrees(math.atan2(s, d[2])))


def read_mjcf(path: str, data: bytes, root: Node, packages: dict[str, str]) -> Robot:
    """The bodies of an MJCF document (the world body's own geoms are not a link).

    Raises
    ------
    InputError
        Not ``<mujoco>``, an ``<include>``, a bad number, an undefined class or mesh.
    """
    if root.tag != "mujoco":
        raise InputError(path, f"the root element is <{root.tag}>, not <mujoco>", "give an MJCF file")
    for node in root.iter("include"):
        raise InputError(f"{path}: line {node.line}", "<include> is not read", "give the file with includes expanded")
    context = _Context(path, root)
    links: list[Link] = []
    for world in root.findall("worldbody"):
        for node, childclass, _frame in _children(context, world, "main", None):
            if node.tag == "body":
                _body(context, node, childclass, links)
    notes = ['<compiler inertiafromgeom="true">: MuJoCo ignores every declared <inertial> and computes '
             'the bodies from their geoms'] if context.from_geoms else []
    return Robot(path, "mjcf", data, links, notes)


def _children(context: _Context, node: Node, childclass: str, frame: Placement | None):
    """Child elements with their default class, looking through ``<frame>`` elements (MuJoCo 3):
    the placement of the frames around a child (None: none) comes with it."""
    from p3d_cli.placement import then

    for child in node.children:
        if child.tag == "frame":
            where = f"{context.path}: frame line {child.line}"
            pos = numbers(child.attrib.get("pos"), 3, f"{where}: pos")
            own = Placement(None, context.rotation(child.attrib, where), None if pos is None else np.array(pos))
            yield from _children(context, child, child.attrib.get("childclass", childclass),
                                 own if frame is None else then(own, frame))
        else:
            yield child, childclass, frame


def _body(context: _Context, node: Node, outer_class: str, links: list[Link]) -> None:
    name = node.attrib.get("name") or f"body@line{node.line}"
    where = f"{context.path}: body {name!r}"
    childclass = node.attrib.get("childclass", outer_class)
    link = Link(name, node)
    links.append(link)
    counts = {"collision": 0, "visual": 0}
    for child, cls, frame in _children(context, node, childclass, None):
        if child.tag == "body":
            _body(context, child, cls, links)
        elif child.tag == "geom":
            a = context.attributes(child, cls)
            role = "visual" if a.get("contype", "1") == "0" and a.get("conaffinity", "1") == "0" else "collision"
            geom_where = f"{where}: geom {a['name']!r}" if "name" in a else f"{where}: {role} geom[{counts[role]}]"
            counts[role] += 1
            try:
                geom = _geom(context, a, geom_where, role, frame)
            except _Skipped as skipped:
                link.problems.append(f"{geom_where}: {skipped}")
                continue
            link.geoms(role).append(geom)
        elif child.tag == "inertial":
            a = context.attributes(child, cls)
            link.inertial_node = child
            link.inertial = _inertial(context, a, f"{where}: inertial")


class _Skipped(Exception):
    """A geom p3d cannot measure (a plane, height field, inline mesh): reported, not fatal."""


def _geom(context: _Context, a: dict[str, str], where: str, role: str, frame: Placement | None) -> Geom:
    kind = a.get("type", "mesh" if "mesh" in a else "sphere")
    size = numbers(a.get("size"), (1, 2, 3), f"{where}: size", [])
    pos = numbers(a.get("pos"), 3, f"{where}: pos", [0.0, 0.0, 0.0])
    rotation = context.rotation(a, where)
    scale = None
    if "fromto" in a and kind in ("capsule", "cylinder", "box", "ellipsoid"):
        ends = np.array(numbers(a["fromto"], 6, f"{where}: fromto"))
        with np.errstate(over="ignore"):  # ends near float64's limit: refused just below
            axis = ends[3:] - ends[:3]
        half = 0.5 * math.hypot(*axis)  # hypot: no overflow in the squares
        if not 0 < half < math.inf:
            raise InputError(where, "fromto's ends are equal or too far apart", "give two different points")
        pos, rotation = list(0.5 * ends[:3] + 0.5 * ends[3:]), z_to(axis)
        size = [size[0], half] if kind in ("capsule", "cylinder") else [size[0], size[1] if len(size) > 1
                                                                         else size[0], half]
    if kind == "mesh":
        mesh = a.get("mesh")
        if mesh not in context.meshes:
            raise InputError(where, f"mesh {mesh!r} is not an asset", "declare it under <asset>")
        thing, scale = context.meshes[mesh]
        if not thing:
            raise _Skipped(f"mesh {mesh!r} has no file (inline or generated meshes are not read)")
        if not os.path.isfile(thing):
            raise InputError(where, f"mesh {mesh!r}: {thing}: no such file",
                             "mesh files are found under the compiler's meshdir, relative to the model")
    elif kind in ("plane", "hfield", "sdf"):
        raise _Skipped(f"a {kind} geom has no volume p3d can measure")
    else:
        need = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
        if kind not in need:
            raise InputError(where, f"type {kind!r} is not a MuJoCo geom type", "use sphere, capsule, box, ...")
        if len(size) < need[kind] or any(s <= 0 for s in size[:need[kind]]):
            raise InputError(where, f"a {kind} needs {need[kind]} positive size numbers, has {size}",
                             "give the half-sizes")
        s = size
        thing = {"sphere": lambda: spec("sphere", s[0]), "capsule": lambda: spec("capsule", s[0], s[1]),
                 "cylinder": lambda: spec("cylinder", s[0], s[0], s[1]),
                 "box": lambda: spec("box", *s[:3]), "ellipsoid": lambda: spec("ellipsoid", *s[:3])}[kind]()
    from p3d_cli.placement import then

    placement = Placement(scale, rotation, None if not any(pos) else np.array(pos))
    return Geom(thing, placement if frame is None else then(placement, frame), where, role)


def _inertial(context: _Context, a: dict[str, str], where: str):
    mass = numbers(a.get("mass"), 1, f"{where}: mass")
    pos = numbers(a.get("pos"), 3, f"{where}: pos", [0.0, 0.0, 0.0])
    if mass is None:
        raise InputError(where, "has no mass", "give mass= in kg")
    if "fullinertia" in a:
        xx, yy, zz, xy, xz, yz = numbers(a["fullinertia"], 6, f"{where}: fullinertia")
        tensor = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    elif "diaginertia" in a:
        tensor = np.diag(numbers(a["diaginertia"], 3, f"{where}: diaginertia"))
    else:
        raise InputError(where, "has neither diaginertia nor fullinertia", "give the inertia")
    return rotated_inertial(mass[0], pos, context.rotation(a, where), tensor)

