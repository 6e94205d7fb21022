"""Running one command over many inputs: expansion of directories, and per-input errors.

A failing input yields an error record and the batch goes on; nothing already printed is lost.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator

from p3d_cli.errors import InputError, P3DError


@dataclass(frozen=True)
class Outcome:
    """One input's result or its error."""

    source: str
    result: object = None
    error: P3DError | None = None


def expand_inputs(inputs: Iterable[str]) -> Iterator[str | InputError]:
    """Inputs as given, with each directory replaced by the mesh files under it (sorted).

    A directory with no mesh files yields an ``InputError`` in its place.
    """
    from p3d_cli.io import is_mesh_path

    for item in inputs:
        if item != "-" and os.path.isdir(item):
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


def run_each(inputs: Iterable[str], work: Callable[[str], object]) -> Iterator[Outcome]:
    """Apply ``work`` to each input in order, turning p3d's errors into error outcomes."""
    for item in expand_inputs(inputs):
        if isinstance(item, P3DError):
            yield Outcome(item.where, None, item)
            continue
        try:
            yield Outcome(item, work(item))
        except P3DError as exc:
            yield Outcome(item, None, exc)
