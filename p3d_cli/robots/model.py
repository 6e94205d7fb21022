"""What p3d reads from a robot description: links, their geometry and declared inertials.

Every format (``urdf``, ``mjcf``, ``sdf``) is read into these types, in the description's own
units (metres, kilograms: URDF, SDF and MJCF all use SI) and in each link's own frame:

- a ``Geom`` is one piece of visual or collision geometry: a mesh path or a shape spec, with
  the ``Placement`` (mesh scale, then the rotation, then the translation) that puts it in the
  link frame;
- an ``Inertial`` is a declared mass, centre of mass and inertia tensor, the tensor already
  turned into the link frame (``I_link = R I Rᵀ`` for an inertial frame rotated by ``R``);
- a ``Link`` holds both, and the XML element it came from, so that ``fill`` can rewrite it.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

from p3d_cli.errors import InputError, ReadError
from p3d_cli.geometry.placement import Placement
from p3d_cli.robots.xmltree import Document, Node


@dataclass(frozen=True)
class Geom:
    """One piece of geometry in a link's frame.

    Attributes
    ----------
    thing : str
        A mesh path (resolved) or a shape spec (``box:0.1,0.2,0.3``, half-extents).
    placement : Placement
    where : str
        ``robot.urdf: link 'forearm': collision[0]``, for messages.
    role : {"collision", "visual"}
    density, mass : float or None
        What the description says the geom is made of (MJCF's per-geom ``density`` and
        ``mass``, kg/m³ and kg); None: it says nothing, and the caller's density applies.
    """

    thing: str
    placement: Placement
    where: str
    role: str = "collision"
    density: float | None = None
    mass: float | None = None


@dataclass(frozen=True)
class Inertial:
    """A declared inertial, in the link frame.

    Attributes
    ----------
    mass : float
    center : (3,) float64
    inertia : (3, 3) float64
        About the centre of mass, axes of the link frame, positive convention.
    """

    mass: float
    center: np.ndarray
    inertia: np.ndarray


@dataclass
class Link:
    """One link (URDF, SDF) or body (MJCF).

    Attributes
    ----------
    name : str
    collision, visual : list of Geom
    inertial : Inertial or None
        As declared (None: the description declares none).
    node : Node
        The element of the link (``<link>`` or ``<body>``).
    inertial_node : Node or None
        The element of the declared inertial.
    problems : list of str
        What reading found wrong with its geometry (an unsupported geometry), kept for reports.
    """

    name: str
    node: Node
    collision: list[Geom] = field(default_factory=list)
    visual: list[Geom] = field(default_factory=list)
    inertial: Inertial | None = None
    inertial_node: Node | None = None
    problems: list[str] = field(default_factory=list)

    def geoms(self, role: str) -> list[Geom]:
        """The link's ``collision`` or ``visual`` geometry."""
        return self.collision if role == "collision" else self.visual


@dataclass
class Robot:
    """A robot description as read.

    Attributes
    ----------
    path : str
    format : {"urdf", "mjcf", "sdf"}
    doc : Document
        The file as read (``fill`` edits its bytes; included files are their nodes' ``doc``).
    links : list of Link
    notes : list of str
        What the whole file says that changes how its inertials are used (MJCF's
        ``inertiafromgeom="true"``: MuJoCo ignores every declared inertial).
    """

    path: str
    format: str
    doc: Document
    links: list[Link]
    notes: list[str] = field(default_factory=list)

    @property
    def data(self) -> bytes:
        """The description's bytes, as read."""
        return self.doc.data


def spec(shape) -> str:
    """The spec of ``shape`` (a ``p3d_cli.shapes`` object) with full-precision numbers (``repr``
    round-trips a float64): a reader maps its format's primitive onto a shape class, and the
    class says how its spec is written."""
    return f"{shape.name}:" + ",".join(repr(float(v)) for v in shape.numbers())


def inertia_matrix(ixx: float, ixy: float, ixz: float, iyy: float, iyz: float, izz: float) -> np.ndarray:
    """The symmetric tensor of the six numbers URDF and SDF write."""
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]], dtype=np.float64)


def rotated_inertial(mass: float, center, rotation, inertia) -> Inertial:
    """An inertial whose tensor is written in a frame rotated by ``rotation`` from the link's."""
    r = np.eye(3) if rotation is None else np.asarray(rotation, dtype=np.float64)
    return Inertial(float(mass), np.asarray(center, dtype=np.float64), r @ inertia @ r.T)


#: Environment variables naming folders of ROS packages and of Gazebo models.
PACKAGE_VARIABLES = ("ROS_PACKAGE_PATH",)
MODEL_VARIABLES = ("GZ_SIM_RESOURCE_PATH", "IGN_GAZEBO_RESOURCE_PATH", "GAZEBO_MODEL_PATH", "SDF_PATH")


def resolve_uri(uri: str, base: str, packages: dict[str, str], where: str, folder: bool = False) -> str:
    """The file a mesh URI names: ``package://NAME/rest``, ``model://NAME/rest``, ``file://``,
    or a path relative to the description's folder ``base``.

    Packages are looked up in ``packages`` (NAME -> folder) first, then in the folders of
    ``ROS_PACKAGE_PATH`` (``model://``: ``GZ_SIM_RESOURCE_PATH`` and its older names), where a
    package is a sub-folder named NAME, then near the description (``nearby_packages``: the
    package it sits in, and packages beside the folders above it).

    Parameters
    ----------
    folder : bool
        A folder may be named too (an SDF ``<include>``'s model folder).

    Raises
    ------
    InputError
        The file does not exist, or is not a regular file (a FIFO or device beside the model
        would block the read), naming the URI and how to point p3d at the package.
    """
    for scheme, variables in (("package://", PACKAGE_VARIABLES), ("model://", MODEL_VARIABLES)):
        if uri.startswith(scheme):
            name, _, rest = uri[len(scheme):].partition("/")
            path = _in_package(name, rest, packages, variables, folder, base)
            if path is None:
                raise ReadError(where, f"{'model' if folder else 'mesh'} {uri}: no such file",
                                 f"give package_paths={name}=DIR (the folder of package {name})")
            return _regular(path, uri, where, folder)
    path = uri[len("file://"):] if uri.startswith("file://") else uri
    if not os.path.isabs(path):
        path = os.path.join(base, path)
    if not os.path.exists(path):
        raise ReadError(where, f"{'model' if folder else 'mesh'} {uri}: no such file",
                         "paths are relative to the description's folder")
    return _regular(path, uri, where, folder)


def _regular(path: str, uri: str, where: str, folder: bool) -> str:
    import stat

    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise ReadError(where, f"mesh {uri}: {exc.strerror or exc}", "check the path") from None
    if not (stat.S_ISREG(mode) or (folder and stat.S_ISDIR(mode))):
        raise ReadError(where, f"mesh {uri} is not a regular file (a folder, FIFO or device)", "name a mesh file")
    return path


def package_folders(name: str, packages: dict[str, str], variables=PACKAGE_VARIABLES,
                    base: str | None = None) -> list[str]:
    """Where package ``name`` may be, in the order it is looked for: the map's folder, a
    sub-folder NAME of each folder of the environment ``variables``, then near the description
    in folder ``base`` (``nearby_packages``)."""
    folders = [packages[name]] if name in packages else []
    for variable in variables:
        for root in os.environ.get(variable, "").split(os.pathsep):
            if root:
                folders.append(os.path.join(root, name))
    if base is not None:
        folders += nearby_packages(name, base)
    return folders


def _in_package(name: str, rest: str, packages: dict[str, str], variables, folder: bool = False,
                base: str | None = None) -> str | None:
    for place in package_folders(name, packages, variables, base):
        path = os.path.join(place, rest)
        if os.path.exists(path) and (folder or not os.path.isdir(path)):
            return path
    return None


#: Folders above a description searched for its packages (a workspace's src/NAME/urdf/x.urdf
#: is three below the folder that holds its packages).
NEARBY_LEVELS = 6


def nearby_packages(name: str, base: str) -> list[str]:
    """Folders that may be package (or Gazebo model) ``name``, near a description in folder
    ``base``, nearest first: walking up from ``base``, a folder whose ``package.xml`` names the
    package (as ROS finds the package a file is in) or that is itself called ``name``, and a
    folder ``name`` inside it (packages side by side in a workspace, models in a models folder).
    ``NEARBY_LEVELS`` folders up at most. Only folders that exist are returned."""
    out: list[str] = []
    here = os.path.abspath(base)
    for _ in range(NEARBY_LEVELS + 1):
        if os.path.basename(here) == name or _names_package(os.path.join(here, "package.xml"), name):
            out.append(here)
        beside = os.path.join(here, name)
        if os.path.isdir(beside) and beside not in out:
            out.append(beside)
        up = os.path.dirname(here)
        if up == here:
            break
        here = up
    return out


def _names_package(manifest: str, name: str) -> bool:
    """Whether the ROS manifest ``manifest`` (a package.xml) declares package ``name``."""
    import re

    try:
        with open(manifest, "rb") as f:
            text = f.read(1 << 16)
    except OSError:
        return False
    found = re.search(rb"<name>\s*([^<\s]+)\s*</name>", text)
    return found is not None and found.group(1).decode("utf-8", "replace") == name


def parse_package_paths(items) -> dict[str, str]:
    """``["NAME=DIR", ...]`` (or a mapping) as a mapping of package names to folders.

    Raises
    ------
    InputError
        An item without ``=``.
    """
    if isinstance(items, dict):
        return {str(k): str(v) for k, v in items.items()}
    out = {}
    for item in items or ():
        name, sep, folder = str(item).partition("=")
        if not sep or not name or not folder:
            raise InputError("package_paths", f"{item!r} is not NAME=DIR", "write e.g. ur_description=./ur")
        out[name] = folder
    return out
