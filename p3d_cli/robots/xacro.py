"""xacro files expanded with the ``xacro`` package (the ``robots`` extra), without ROS.

The ``xacro`` package on the Python index resolves ``$(find NAME)`` through ROS's package
index (``ament_index_python``), which a plain install does not have. p3d resolves it through the
same package map as ``package://NAME/...`` URIs (``package_paths``, then ``ROS_PACKAGE_PATH``),
by handing xacro its own ``find`` substitution for the one expansion. Arguments
(``xacro:arg``) are given as ``NAME:=VALUE``, as on xacro's command line.

The expanded document is what p3d reads; it has no file of its own, so ``fill`` writes it to
the output named (never over the xacro source).
"""

from __future__ import annotations

import contextlib
import os

from p3d_cli.errors import InputError, MissingExtraError, install_hint
from p3d_cli.robots.model import package_folders
from p3d_cli.robots.xmltree import Node, parse_xml

INSTALL = install_hint("robots", "'xacro>=2.0'")


def parse_xacro_args(items) -> dict[str, str]:
    """``["name:=value", ...]`` (or a mapping) as a mapping.

    Raises
    ------
    InputError
        An item without ``:=``.
    """
    if isinstance(items, dict):
        return {str(k): str(v) for k, v in items.items()}
    out = {}
    for item in items or ():
        name, sep, value = str(item).partition(":=")
        if not sep or not name:
            raise InputError("xacro_args", f"{item!r} is not NAME:=VALUE", "write e.g. prefix:=left_")
        out[name] = value
    return out


def package_folder(name: str, packages: dict[str, str], base: str | None = None) -> str | None:
    """The folder of package ``name``: the map's, else the first folder of
    ``model.package_folders`` that exists (``ROS_PACKAGE_PATH``, then near the xacro file's
    folder ``base``)."""
    if name in packages:
        return packages[name]
    return next((f for f in package_folders(name, packages, base=base) if os.path.isdir(f)), None)


def expand_xacro(path: str, root: Node, packages: dict[str, str], xacro_args=None) -> Node:
    """The tree of the URDF (or SDF) the xacro file at ``path`` expands to.

    Raises
    ------
    MissingExtraError
        The ``xacro`` package is not installed.
    InputError
        xacro refuses the file (its message, naming the file), or ``$(find NAME)`` names a
        package not in the map.
    """
    try:
        import xacro
        import xacro.substitution_args as substitution
    except ImportError:
        raise MissingExtraError(path, "is a xacro file, and expanding it needs the xacro package",
                                f"{INSTALL}; or expand it yourself: xacro {os.path.basename(path)} "
                                "> robot.urdf") from None
    arguments = parse_xacro_args(xacro_args)
    missing: list[str] = []

    def find(name: str) -> str:
        # xacro's own _eval_find(pkg) asks ament_index_python for the package's share folder.
        folder = package_folder(name, packages, os.path.dirname(os.path.abspath(path)))
        if folder is None:
            missing.append(name)
            raise substitution.SubstitutionException(f"package {name} not found")
        return os.path.abspath(folder)

    with _patched(substitution, "_eval_find", find), _quiet():
        try:
            document = xacro.process_file(path, mappings=arguments)
        except Exception as exc:  # xacro raises its own and the standard library's errors
            if missing:
                raise InputError(path, f"$(find {missing[0]}) names a package p3d was not told of",
                                 f"give package_paths={missing[0]}=DIR") from None
            text = " ".join(str(exc).split())
            raise InputError(path, f"xacro could not expand it ({type(exc).__name__}: {text})",
                             "fix the file or give its arguments: xacro_args=NAME:=VALUE") from None
    data = document.toxml(encoding="utf-8")
    return parse_xml(data, f"{path} (expanded by xacro)")


@contextlib.contextmanager
def _patched(module, name: str, value):
    old = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, old)


@contextlib.contextmanager
def _quiet():
    """xacro prints its warnings (deprecations, unused arguments) to stderr: p3d's stderr is its
    own diagnostics, so they are kept out of it."""
    import io
    import sys

    saved = sys.stderr
    sys.stderr = io.StringIO()
    try:
        yield
    finally:
        sys.stderr = saved
