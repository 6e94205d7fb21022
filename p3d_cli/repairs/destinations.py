"""Where a batch of repairs writes: an output folder mirroring the inputs' tree.

A file found in a folder the user named keeps its place below that folder (``parts/`` ->
``fixed/sub/a.stl`` for ``parts/sub/a.stl``, as ``cp -r parts/. fixed/`` would place it);
any other file keeps the relative path it was given by (``parts/a.stl`` ->
``fixed/parts/a.stl``), or its name when that path is absolute or climbs out of the working
folder. ``output_format`` changes the extension. Two inputs that would land on one output are
an error for the second (``OutputError``), never an overwrite (one input named twice is one
input: its repair, the same both times, goes to its one place), and so is an input that lies in
the output folder itself (a repair written by an earlier run into a folder inside the inputs').
"""

from __future__ import annotations

import os
from typing import Iterable

from p3d_cli.errors import OutputError


def mirrored(items: Iterable[str], roots: Iterable[str], folder: str, extension: str | None = None) -> dict:
    """The output path of every input.

    Parameters
    ----------
    items : iterable of str
        The batch's input paths (directories already expanded into their files).
    roots : iterable of str
        The folders the user named (their files are placed relative to them).
    folder : str
        The output folder.
    extension : str, optional
        The output extension (with its dot), replacing the input's.

    Returns
    -------
    dict
        Input path -> output path, or -> ``OutputError`` for an input whose place another
        input took.
    """
    folders = sorted((os.path.join(os.path.normpath(r), "") for r in roots), key=len, reverse=True)
    inside = os.path.join(os.path.realpath(folder), "")
    out: dict = {}
    taken: dict[str, str] = {}
    for item in items:
        if item == "-":
            out[item] = OutputError(folder, "standard input has no name to mirror",
                                    "give the mesh by path, or write it with -o FILE")
            continue
        if os.path.realpath(item).startswith(inside):
            out[item] = OutputError(item, f"lies in the output folder {folder} (written by an earlier repair?)",
                                    "write the repairs to a folder outside the ones being read")
            continue
        relative = _relative(item, folders)
        if extension is not None:
            relative = os.path.splitext(relative)[0] + extension
        target = os.path.join(folder, relative)
        key = os.path.normcase(os.path.normpath(target))
        if key in taken and taken[key] != item:
            out[item] = OutputError(target, f"is already the output of {taken[key]}",
                                    "give the inputs distinct paths or names")
            continue
        taken[key] = item
        out[item] = target
    return out


def _relative(item: str, folders: list[str]) -> str:
    path = os.path.normpath(item)
    for folder in folders:
        if os.path.join(path, "").startswith(folder) and path != os.path.normpath(folder):
            return os.path.relpath(path, folder)
    if os.path.isabs(path) or path.split(os.sep)[0] == os.pardir:
        return os.path.basename(path)
    return path
