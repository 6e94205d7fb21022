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

What MuJoCo's compiler expands is expanded the same way (checked against MuJoCo in the tests):
``<include file>`` puts the children of the included file's ``<mujoco>`` in its place (paths
relative to the main model's folder, as MuJoCo resolves nested includes too; a file included
twice is refused, as MuJoCo refuses it); ``<replicate count offset euler sep>`` repeats its
children, the i-th copy moved i times by the offset and turned i times by the euler angles,
each body named with ``sep`` and the index appended (an inner replicate's suffix first);
``<frame>`` places its children. Elements keep the file they were written in, so ``fill``
edits a body's inertial where it is written. Limits: ``MAX_INCLUDES`` files and
``MAX_BODIES`` bodies after expansion (a replicate of replicates multiplies).

Per-geom ``density`` (kg/m³, MuJoCo's default 1000) and ``mass`` are kept on each geom, so a
body measured from its geoms has the mass MuJoCo gives it.

Which geoms are a body's collision geometry: those that can collide (``contype`` or
``conaffinity`` non-zero, MuJoCo's default); the others (both zero) are its visual geometry.
"""

from __future__ import annotations

import math
import os

import numpy as np

from p3d_cli.errors import InputError, ReadError, UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.robots.model import Geom, Link, Robot, rotated_inertial, spec
from p3d_cli.robots.xmltree import Node, numbers, read_xml, regular_file
from p3d_cli.shapes import Box, Capsule, Cylinder, Ellipsoid, Sphere

#: Files one model may include (MuJoCo itself includes each file once).
MAX_INCLUDES = 256
#: Bodies a model may expand to (nested ``<replicate>`` multiplies their counts).
MAX_BODIES = 100_000
#: MuJoCo's default geom density, kg/m³.
DEFAULT_DENSITY = 1000.0

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

    def _read_defaults(self, top: Node, inherited: dict, name: str) -> None:
        """Each default class's attributes, nested classes inheriting (a stack, not recursion)."""
        stack = [(top, inherited, name)]
        while stack:
            node, outer, fallback = stack.pop()
            own = {tag: dict(values) for tag, values in outer.items()}
            for child in node.children:
                if child.tag != "default":
                    own.setdefault(child.tag, {}).update(child.attrib)
            self.defaults[node.attrib.get("class", fallback)] = own
            stack.extend((child, own, "") for child in reversed(node.findall("default")))

    def childclass(self, node: Node, outer: str) -> str:
        """The class a ``<body>``'s or ``<frame>``'s children take (MuJoCo refuses an undefined one)."""
        name = node.attrib.get("childclass", outer)
        if name not in self.defaults and name != "main":
            raise InputError(f"{node.where}", f"<{node.tag}> names childclass {name!r}, which is not defined",
                             "define it under <default>")
        return name

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
        from p3d_cli.geometry.rotation import rotation_from_axis_degrees, rotation_from_quaternion

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
    from p3d_cli.geometry.rotation import rotation_from_axis_degrees

    length = math.hypot(*direction)
    if not 0 < length < math.inf:
        raise UsageError("zaxis", "is zero or not finite", "")
    d = direction / length
    axis = np.cross([0.0, 0.0, 1.0], d)
    s = np.linalg.norm(axis)
    if s < 1e-15:
        return np.eye(3) if d[2] > 0 else np.diag([1.0, -1.0, -1.0])
    return rotation_from_axis_degrees(axis / s, math.degrees(math.atan2(s, d[2])))


def read_mjcf(path: str, root: Node, packages: dict[str, str]) -> Robot:
    """The bodies of an MJCF document (the world body's own geoms are not a link).

    Raises
    ------
    InputError
        Not ``<mujoco>``, a bad ``<include>`` or ``<replicate>``, a bad number, an undefined
        class or mesh, more than ``MAX_BODIES`` bodies.
    """
    if root.tag != "mujoco":
        raise InputError(path, f"the root element is <{root.tag}>, not <mujoco>", "give an MJCF file")
    _expand_includes(path, root)
    context = _Context(path, root)
    links: list[Link] = []
    for world in root.findall("worldbody"):
        stack = [(node, cls, suffix) for node, cls, _frame, suffix in
                 reversed(_contents(context, world, "main", None, "")) if node.tag == "body"]
        while stack:
            node, cls, suffix = stack.pop()
            children = _body(context, node, cls, suffix, links)
            stack.extend(reversed(children))
            if len(links) + len(stack) > MAX_BODIES:
                raise InputError(path, f"expands to more than {MAX_BODIES} bodies", "is a <replicate> count "
                                 "too large?")
    notes = ['<compiler inertiafromgeom="true">: MuJoCo ignores every declared <inertial> and computes '
             'the bodies from their geoms'] if context.from_geoms else []
    return Robot(path, "mjcf", root.doc, links, notes)


def _expand_includes(path: str, root: Node) -> None:
    """Put each ``<include>``'s file in its place (its root's children), as MuJoCo does."""
    folder = os.path.dirname(path)
    seen = {os.path.realpath(path)}
    while True:
        include = next(root.iter("include"), None)
        if include is None:
            return
        where = f"{include.where}: <include>"
        file = include.attrib.get("file")
        if not file:
            raise InputError(where, "has no file", "give file=")
        full = file if os.path.isabs(file) else os.path.join(folder, file)
        real = os.path.realpath(full)
        if real in seen:
            raise InputError(where, f"{file} is included twice (or includes itself)",
                             "include each file once, as MuJoCo requires")
        seen.add(real)
        if len(seen) > MAX_INCLUDES:
            raise InputError(where, f"more than {MAX_INCLUDES} files included", "is the model looping?")
        included = read_xml(full, where)
        if included.tag != "mujoco":
            raise InputError(f"{full}: line {included.line}", f"the root element is <{included.tag}>, not "
                             "<mujoco>", "an included file is an MJCF <mujoco> element")
        parent = include.parent
        for child in included.children:
            child.parent = parent
        at = parent.children.index(include)
        parent.children[at:at + 1] = included.children


def _contents(context: _Context, node: Node, childclass: str, frame: Placement | None,
              suffix: str) -> list[tuple[Node, str, Placement | None, str]]:
    """Child elements with their default class, the placement of the ``<frame>`` and
    ``<replicate>`` elements around them (None: none) and the name suffix replicates give,
    looking through those two (a stack, not recursion: deep nesting cannot exhaust it)."""
    from p3d_cli.geometry.placement import then

    out: list[tuple[Node, str, Placement | None, str]] = []
    stack = [(child, childclass, frame, suffix) for child in reversed(node.children)]
    while stack:
        child, cls, outer, tail = stack.pop()
        if child.tag == "frame":
            where = f"{context.path}: frame line {child.line}"
            pos = numbers(child.attrib.get("pos"), 3, f"{where}: pos")
            own = Placement(None, context.rotation(child.attrib, where), None if pos is None else np.array(pos))
            inner = context.childclass(child, cls)
            placed = own if outer is None else then(own, outer)
            stack.extend((c, inner, placed, tail) for c in reversed(child.children))
        elif child.tag == "replicate":
            copies = _replicas(context, child)
            if len(copies) * max(len(child.children), 1) + len(stack) + len(out) > MAX_BODIES:
                raise InputError(child.where, f"<replicate> expands to more than {MAX_BODIES} elements",
                                 "give a smaller count")
            sep = child.attrib.get("sep", "")
            for i, own in reversed(list(enumerate(copies))):
                placed = own if outer is None else then(own, outer)
                stack.extend((c, cls, placed, f"{sep}{i}{tail}") for c in reversed(child.children))
        else:
            out.append((child, cls, outer, tail))
    return out


def _replicas(context: _Context, node: Node) -> list[Placement]:
    """The placements of a ``<replicate>``'s copies: the i-th is the step (euler, then offset)
    applied i times."""
    from p3d_cli.geometry.placement import IDENTITY, then

    where = f"{node.where}: <replicate>"
    count = numbers(node.attrib.get("count"), 1, f"{where}: count")
    if count is None or count[0] != int(count[0]) or not 1 <= count[0] <= MAX_BODIES:
        raise InputError(where, f"count {node.attrib.get('count')!r} is not a whole number from 1 to "
                         f"{MAX_BODIES}", "give count=N")
    offset = numbers(node.attrib.get("offset"), 3, f"{where}: offset", [0.0, 0.0, 0.0])
    rotation = context.rotation({"euler": node.attrib["euler"]}, where) if "euler" in node.attrib else None
    step = Placement(None, rotation, np.array(offset) if any(offset) else None)
    copies = [IDENTITY]
    for _ in range(int(count[0]) - 1):
        copies.append(then(copies[-1], step))
    return copies


def _body(context: _Context, node: Node, outer_class: str, suffix: str, links: list[Link]) -> list:
    """The body's link (appended to ``links``); returns its child bodies, to be read next."""
    name = node.attrib.get("name")
    # An unnamed body is named by its MuJoCo body id (world 0, then depth first, as compiled): a
    # line number would change when fill inserts an inertial above it.
    name = name + suffix if name else f"body#{len(links) + 1}"
    where = f"{node.doc.path if node.doc else context.path}:{node.line}: body {name!r}"
    childclass = context.childclass(node, outer_class)
    link = Link(name, node)
    links.append(link)
    counts = {"collision": 0, "visual": 0}
    bodies = []
    for child, cls, frame, tail in _contents(context, node, childclass, None, suffix):
        if child.tag == "body":
            bodies.append((child, cls, tail))
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
    return bodies


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
        need = 1 if kind in ("capsule", "cylinder") else 2
        if len(size) < need:
            raise InputError(where, f"a {kind} given by fromto needs {'its radius' if need == 1 else 'two radii'} "
                             f"in size, has {len(size)} number(s)", "give size=\"R\"" if need == 1 else
                             "give size=\"RX RY\"")
        pos, rotation = list(0.5 * ends[:3] + 0.5 * ends[3:]), z_to(axis)
        size = [size[0], half] if need == 1 else [size[0], size[1], half]
    if kind == "mesh":
        mesh = a.get("mesh")
        if mesh not in context.meshes:
            raise InputError(where, f"mesh {mesh!r} is not an asset", "declare it under <asset>")
        thing, scale = context.meshes[mesh]
        if not thing:
            raise _Skipped(f"mesh {mesh!r} has no file (inline or generated meshes are not read)")
        if not os.path.exists(thing):
            raise ReadError(where, f"mesh {mesh!r}: {thing}: no such file",
                             "mesh files are found under the compiler's meshdir, relative to the model")
        regular_file(thing, where, f"mesh {mesh!r}:")
    elif kind in ("plane", "hfield", "sdf"):
        raise _Skipped(f"a {kind} geom has no volume p3d can measure")
    else:
        counts = {"sphere": 1, "capsule": 2, "cylinder": 2, "box": 3, "ellipsoid": 3}
        if kind not in counts:
            raise InputError(where, f"type {kind!r} is not a MuJoCo geom type", "use sphere, capsule, box, ...")
        if len(size) < counts[kind] or any(s <= 0 for s in size[:counts[kind]]):
            raise InputError(where, f"a {kind} needs {counts[kind]} positive size numbers, has {size}",
                             "give the half-sizes")
        s = size
        # MuJoCo's sizes are half-sizes: a capsule's and a cylinder's radius and half-length.
        thing = spec({"sphere": lambda: Sphere(s[0]), "capsule": lambda: Capsule(s[0], s[1]),
                      "cylinder": lambda: Cylinder(s[0], s[1]),
                      "box": lambda: Box(*s[:3]), "ellipsoid": lambda: Ellipsoid(*s[:3])}[kind]())
    from p3d_cli.geometry.placement import then

    placement = Placement(scale, rotation, None if not any(pos) else np.array(pos))
    mass = numbers(a.get("mass"), 1, f"{where}: mass")
    density = numbers(a.get("density"), 1, f"{where}: density")
    if (mass is not None and mass[0] < 0) or (density is not None and density[0] < 0):
        raise InputError(where, "has a negative mass or density", "give mass >= 0 or density >= 0")
    return Geom(thing, placement if frame is None else then(placement, frame), where, role,
                density=None if density is None else density[0], mass=None if mass is None else mass[0])


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

