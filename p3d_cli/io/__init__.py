"""Reading meshes: one module per format, one record per format in ``formats.FORMATS``.

Every reader has the signature ``load(raw: RawInput) -> MeshSource`` and returns plain
arrays: no trimesh or meshio object crosses this package's boundary. The format comes from
the content where the bytes say it (``ply``, ``OFF``, a binary STL's size), else from the
extension; an explicit format name overrides both (``p3d_cli.io.formats``).
"""

from __future__ import annotations

import dataclasses
from typing import BinaryIO

from p3d_cli.io.formats import FORMATS, NEVER_MESHES, detect_format, format_names, is_mesh_file, is_mesh_path, read
from p3d_cli.io.raw import RawInput, open_input
from p3d_cli.io.source import MeshSource

__all__ = ["FORMATS", "NEVER_MESHES", "MeshSource", "RawInput", "load_mesh", "detect_format", "format_names",
           "is_mesh_file", "is_mesh_path", "open_input"]


def load_mesh(source: str, format: str | None = None, stdin: BinaryIO | None = None) -> MeshSource:
    """Open and read one mesh.

    Parameters
    ----------
    source : str
        A path, or ``-`` for standard input.
    format : str, optional
        Format name (``stl``, ``obj``, ``ply``, ``off``, ``gltf``, ``3mf``, ``dae``, ``amf``,
        ``vtp``, an alias such as ``collada`` or ``glb``, or a meshio format name) instead of
        guessing from content and extension.
    stdin : binary stream, optional
        What ``-`` reads; default ``sys.stdin.buffer``.

    Returns
    -------
    MeshSource
        Its ``where`` is the input's name in messages (``<stdin>`` for standard input).

    Raises
    ------
    InputError
        Missing, unreadable, empty, corrupt or unknown input (each with where, what and a hint).
    """
    raw = open_input(source, stdin)
    mesh = read(raw, detect_format(raw, format))
    return dataclasses.replace(mesh, where=raw.where)
