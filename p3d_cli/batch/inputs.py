"""The inputs of a batch: names given, directories searched for mesh files, a list file.

Inputs are the names given (files, directories, ``-`` for standard input) followed by the
lines of a list file (``files_from``; ``p3d --files-from LIST``). A directory becomes the mesh files under it, sorted,
found by extension (``p3d_cli.io.is_mesh_path``); an input that cannot be found or listed
becomes an ``InputError`` in its place, so that the batch reports it at its turn.
"""

from __future__ import annotations

import os
import sys
from typing import Iterable, Iterator

from p3d_cli.errors import InputError, P3DError, UsageError


def expand_inputs(inputs: Iterable[str | InputError]) -> Iterator[str | InputError]:
    """Inputs as given, with each directory replaced by the mesh files under it (sorted).

    A directory with no mesh files yields an ``InputError`` in its place; errors among the
    inputs pass through.
    """
    from p3d_cli.io import is_mesh_path

    for item in inputs:
        if isinstance(item, P3DError):
            yield item
        elif item != "-" and os.path.isdir(item):
            found = []
            for root, dirs, files in os.walk(item):
                dirs.sort()
                found += [os.path.join(root, name) for name in sorted(files) if is_mesh_path(name)]
            if not found:
                yield InputError(item, "directory holds no mesh files",
                                 "p3d reads .stl, .obj, .ply, .off and meshio's formats")
            yield from found
        else:
            yield item


def read_file_list(files_from: str, stdin=None) -> list[str]:
    """The paths listed in ``files_from``, one per line (``-``: standard input).

    Surrounding white space is stripped and blank lines are skipped; relative paths are
    relative to the current directory.

    Raises
    ------
    InputError
        The list cannot be read.
    """
    if files_from == "-":
        stream = stdin if stdin is not None else sys.stdin
        text = stream.read()
        if isinstance(text, bytes):
            text = text.decode("utf-8", "surrogateescape")
    else:
        try:
            with open(files_from, encoding="utf-8", errors="surrogateescape") as f:
                text = f.read()
        except FileNotFoundError:
            raise InputError(files_from, "no such file", "check the path of the list") from None
        except IsADirectoryError:
            raise InputError(files_from, "is a directory",
                             "the list is a text file of paths; pass a directory as an input") from None
        except OSError as exc:
            raise InputError(files_from, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    return [line.strip() for line in text.splitlines() if line.strip()]


def collect_inputs(inputs: Iterable[str], files_from: str | None, command: str) -> list[str | InputError]:
    """All inputs of a batch, expanded: arguments first, then the ``--files-from`` list.

    Raises
    ------
    UsageError
        Nothing to do, or standard input asked for twice.
    InputError
        The list cannot be read.
    """
    given = list(inputs)
    if files_from is not None:
        if files_from == "-" and "-" in given:
            raise UsageError("files_from", "standard input cannot hold both the list and a mesh (-)",
                             "write the list to a file, or give the mesh by path")
        listed = read_file_list(files_from)
        if not listed:
            raise UsageError("files_from", f"{'standard input' if files_from == '-' else files_from} "
                             "lists no files", "write one path per line")
        if files_from == "-" and "-" in listed:
            raise UsageError("files_from", "the list on standard input names - (standard input), which holds the list",
                             "give the mesh by path")
        given += listed
    if not given:
        raise UsageError(command, "no input given",
                         "name mesh files, directories, - for standard input, or a list of files")
    return list(expand_inputs(given))
