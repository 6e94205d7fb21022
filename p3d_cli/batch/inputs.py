"""The inputs of a batch: names given, directories searched for mesh files, a list file.

Inputs are the names given (files, directories, ``-`` for standard input) followed by the
lines of a list file (``files_from``; ``p3d --files-from LIST``). A directory becomes the mesh files under it, sorted,
found by extension (``p3d_cli.io.is_mesh_file``: a ``.xml`` must be a DOLFIN mesh, not a robot
model or a package manifest); an input that cannot be found or listed
becomes an ``InputError`` in its place, so that the batch reports it at its turn.
"""

from __future__ import annotations

import os
import sys
from typing import Iterable, Iterator

from p3d_cli.errors import InputError, P3DError, ReadError, UsageError


def expand_inputs(inputs: Iterable[str | InputError],
                  skipped: dict[str, list[str]] | None = None) -> Iterator[str | InputError]:
    """Inputs as given, with each directory replaced by the mesh files under it (sorted).

    A directory with no mesh files yields an ``InputError`` in its place (naming the kinds of
    file it does hold); errors among the inputs pass through.

    Parameters
    ----------
    inputs : iterable of str or InputError
    skipped : dict, optional
        Filled with the files a directory search passed over, by extension (lower case, with
        its dot; ``""`` for none): ``{".3mf": ["exports/a.3mf"]}``.
    """
    from p3d_cli.io import is_mesh_file

    skipped = {} if skipped is None else skipped
    for item in inputs:
        if isinstance(item, P3DError):
            yield item
        elif "\0" in item:   # no file name holds one: the list was NUL-separated, or is not a list
            yield InputError(item, "the name holds a NUL byte, which no file name can",
                             "a NUL-separated list (find -print0, git ls-files -z) needs -0")
        elif item != "-" and os.path.isdir(item):
            found: list[str] = []
            passed: dict[str, list[str]] = {}
            for root, dirs, files in os.walk(item):
                dirs.sort()
                for name in sorted(files):
                    path = os.path.join(root, name)
                    if is_mesh_file(path):
                        found.append(path)
                    else:
                        passed.setdefault(os.path.splitext(name)[1].lower(), []).append(path)
            for extension, paths in passed.items():
                skipped.setdefault(extension, []).extend(paths)
            if not found:
                yield _no_meshes(item, passed)
            yield from found
        else:
            yield item


def extension_counts(skipped: dict[str, list[str]]) -> str:
    """``2 .3mf, 1 .glb``: the skipped files by extension, most first."""
    counts = sorted(((len(paths), ext or "without extension") for ext, paths in skipped.items()),
                    key=lambda pair: (-pair[0], pair[1]))
    return ", ".join(f"{n} {ext}" for n, ext in counts)


def _no_meshes(directory: str, passed: dict[str, list[str]]) -> InputError:
    hint = "p3d reads .stl, .obj, .ply, .off and meshio's formats"
    if not passed:
        return InputError(directory, "directory holds no mesh files", hint)
    return InputError(directory, "directory holds no mesh files, only files p3d does not read ("
                      + extension_counts(passed) + ")", hint + " (--format NAME reads a named file as NAME)")


def read_file_list(files_from: str, stdin=None, null: bool = False) -> list[str]:
    """The paths listed in ``files_from``, one per line (``-``: standard input).

    Surrounding white space is stripped and blank lines are skipped; relative paths are
    relative to the current directory. With ``null``, paths are separated by NUL bytes instead
    (``git ls-files -z``, ``find -print0``) and kept exactly, spaces and newlines included.
    Bytes that are not UTF-8 are kept as surrogate escapes, so the names open as listed.

    Raises
    ------
    InputError
        The list cannot be read.
    """
    if files_from == "-":
        stream = stdin if stdin is not None else sys.stdin
        data = stream.buffer.read() if null and hasattr(stream, "buffer") else stream.read()
        text = data.decode("utf-8", "surrogateescape") if isinstance(data, bytes) else data
    else:
        try:
            with open(files_from, "rb") as f:
                text = f.read().decode("utf-8", "surrogateescape")
        except FileNotFoundError:
            raise ReadError(files_from, "no such file", "check the path of the list") from None
        except IsADirectoryError:
            raise ReadError(files_from, "is a directory",
                             "the list is a text file of paths; pass a directory as an input") from None
        except OSError as exc:
            raise ReadError(files_from, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    if null:
        return [name for name in text.split("\0") if name]
    return [line.strip() for line in text.splitlines() if line.strip()]


def collect_inputs(inputs: Iterable[str], files_from: str | None, command: str, *,
                   null: bool = False) -> list[str | InputError]:
    """All inputs of a batch, expanded: arguments first, then the ``--files-from`` list.

    Raises
    ------
    UsageError
        Nothing to do, or standard input asked for twice.
    InputError
        The list cannot be read.
    """
    return collect(inputs, files_from, command, null=null)[0]


def collect(inputs: Iterable[str], files_from: str | None, command: str, *,
            null: bool = False) -> tuple[list[str | InputError], dict[str, list[str]]]:
    """As ``collect_inputs``, and the files the directory searches skipped, by extension
    (see ``expand_inputs``)."""
    given = list(inputs)
    if files_from is not None:
        if files_from == "-" and "-" in given:
            raise UsageError("files_from", "standard input cannot hold both the list and a mesh (-)",
                             "write the list to a file, or give the mesh by path")
        listed = read_file_list(files_from, null=null)
        if not listed:
            raise UsageError("files_from", f"{'standard input' if files_from == '-' else files_from} "
                             "lists no files", "write one path per line" + (" (NUL-separated)" if null else ""))
        if files_from == "-" and "-" in listed:
            raise UsageError("files_from", "the list on standard input names - (standard input), which holds the list",
                             "give the mesh by path")
        given += listed
    elif null:
        raise UsageError("null", "given without files_from=", "-0 says how the --files-from list is separated")
    if not given:
        raise UsageError(command, "no input given",
                         "name mesh files, directories, - for standard input, or a list of files")
    skipped: dict[str, list[str]] = {}
    return list(expand_inputs(given, skipped)), skipped
