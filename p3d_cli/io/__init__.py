"""Reading meshes: one module per format, one ``LOADERS`` dict keyed by format.

Every loader has the signature ``load(raw: RawInput) -> MeshSource`` and returns plain
arrays: no trimesh or meshio object crosses this package's boundary. The format comes from
the content where the bytes say it (``ply``, ``OFF``, a binary STL's size), else from the
extension; ``--format`` overrides both.
"""

from __future__ import annotations

import importlib
import os
import re

from p3d_cli.errors import UnknownFormatError
from p3d_cli.io.raw import RawInput, open_input
from p3d_cli.io.source import MeshSource


def _backend(name: str):
    """The module ``p3d_cli.io.<name>``, imported on first use.

    Each format's module (and meshio's, with its xml/tempfile/zlib imports) is imported only
    when a file of that format is read: ``p3d props part.stl`` in a shell loop pays for the
    STL reader alone (issue 7, start-up).
    """
    return importlib.import_module(f"p3d_cli.io.{name}")


def _lazy_loader(name: str):
    def load(raw: RawInput, *args):
        return _backend(name).load(raw, *args)
    load.__name__ = load.__qualname__ = f"{name}.load"
    load.__doc__ = f"``p3d_cli.io.{name}.load``, imported when first called."
    return load


#: Format name -> loader. ``meshio`` covers every other format meshio reads.
LOADERS = {name: _lazy_loader(name) for name in ("stl", "obj", "ply", "off")}
LOADERS["meshio"] = _lazy_loader("meshio_backend")

_EXTENSIONS = {".stl": "stl", ".obj": "obj", ".ply": "ply", ".off": "off"}

#: Files that sit beside meshes in export folders and that no reader takes: a directory search
#: skips them without importing meshio to ask (0.1-0.3 s, more than a small batch's work).
_NEVER_MESHES = frozenset({"", ".txt", ".md", ".rst", ".csv", ".tsv", ".json", ".jsonl", ".yaml", ".yml",
                           ".log", ".mtl", ".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".pdf",
                           ".step", ".stp", ".iges", ".igs", ".3mf", ".zip", ".py", ".html"})

__all__ = ["LOADERS", "MeshSource", "RawInput", "load_mesh", "detect_format", "is_mesh_path"]


#: OFF and its variants (colours, normals, texture coordinates, other dimensions).
_OFF_KEYWORD = re.compile(rb"(ST)?C?N?4?n?OFF")


def _first_word(head: bytes) -> bytes:
    """The first word of the text after blank lines and ``#`` comments (b"" if none)."""
    for line in head.split(b"\n"):
        words = line.split(b"#", 1)[0].split()
        if words:
            return words[0]
    return b""


def is_mesh_path(path: str) -> bool:
    """True when the file name has an extension p3d reads (used to search directories)."""
    ext = os.path.splitext(path)[1].lower()
    if ext in _EXTENSIONS:
        return True
    return ext not in _NEVER_MESHES and _backend("meshio_backend").knows_extension(ext)


def detect_format(raw: RawInput, override: str | None = None) -> str:
    """The format to read ``raw`` with: ``override``, else the content's, else the extension's.

    Raises
    ------
    UnknownFormatError
        Nothing identifies the format.
    """
    if override:
        name = override.lower()
        if name in LOADERS and name != "meshio":
            return name
        if _backend("meshio_backend").knows_format(name):
            return "meshio:" + name
        known = ", ".join(sorted(set(LOADERS) - {"meshio"}))
        raise UnknownFormatError("--format", f"unknown format {override!r}",
                                 f"use one of {known}, or a format name meshio knows")
    head = raw.head(512)
    stripped = head.lstrip()
    if stripped.startswith(b"ply"):
        return "ply"
    if _OFF_KEYWORD.fullmatch(_first_word(head)):
        return "off"
    ext = os.path.splitext(raw.path or "")[1].lower()
    if ext in _EXTENSIONS:
        return _EXTENSIONS[ext]
    if _backend("stl").looks_like_stl(raw):
        return "stl"
    if ext and _backend("meshio_backend").knows_extension(ext):
        return "meshio:" + _backend("meshio_backend").format_for_extension(ext)
    if _backend("obj").looks_like_obj(head):
        return "obj"
    what = f"cannot tell the format of {'this extension' if ext else 'an input without an extension'}"
    raise UnknownFormatError(raw.where, what,
                             "give --format (stl, obj, ply, off, or a meshio format name)")


def load_mesh(source: str, fmt: str | None = None, stdin=None) -> MeshSource:
    """Open and read one mesh.

    Parameters
    ----------
    source : str
        A path, or ``-`` for standard input.
    fmt : str, optional
        Format override (``stl``, ``obj``, ``ply``, ``off`` or a meshio format name).
    stdin : binary stream, optional
        What ``-`` reads; default ``sys.stdin.buffer``.

    Raises
    ------
    InputError
        Missing, unreadable, empty, corrupt or unknown input (each with where, what and a hint).
    """
    raw = open_input(source, stdin)
    name = detect_format(raw, fmt)
    if name.startswith("meshio:"):
        return _backend("meshio_backend").load(raw, name.split(":", 1)[1])
    return LOADERS[name](raw)
