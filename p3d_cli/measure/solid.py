"""What p3d measures: "a thing" the user gave, resolved once into a ``Solid``.

Every library entry (``p3d_cli.measure.props``, ``bounds``, ``check``) starts here, so there is
one place that tells a shape spec from a path, reads a file, and turns Python values (a shape
object, a triangle array, a ``(vertices, faces)`` pair) into the same ``MeshSource`` a file
gives. The road then runs one way: read (here) → validate (as the triangles stream past,
``p3d_cli.mesh.analysis``) → analyse → place → integrate → result.
"""

from __future__ import annotations

import dataclasses
import os
import re
from dataclasses import dataclass
from typing import Any, BinaryIO, TypeGuard, Union

import numpy as np

from p3d_cli.errors import InputError, SpecError, UsageError
from p3d_cli.io.source import MeshSource, array_source, indexed_source
from p3d_cli.shapes import SHAPES, Shape, looks_like_spec, parse_spec
from p3d_cli.warning_codes import CodedWarning

#: What ``as_solid`` takes: a path or spec, a shape, triangles, an indexed mesh, a loaded mesh.
Thing = Union[str, "os.PathLike[str]", Shape, np.ndarray, tuple, MeshSource]


@dataclass(frozen=True)
class Solid:
    """One input, resolved: exactly one of ``shape`` and ``mesh`` is set.

    Attributes
    ----------
    source : str
        The input as the user named it (a path, ``-``, a spec, or ``<array>``), for records.
    shape : Shape or None
        An analytic shape (closed forms).
    mesh : MeshSource or None
        Triangles (or tetrahedra) streamed in blocks.
    warnings : tuple of CodedWarning
        What resolving noticed (a spec that shadows a file of the same name).
    """

    source: str
    shape: Shape | None = None
    mesh: MeshSource | None = None
    warnings: tuple[CodedWarning, ...] = ()

    @property
    def where(self) -> str:
        """The input's name in messages (``<stdin>`` for standard input)."""
        return self.mesh.where if self.mesh is not None else self.source


def as_solid(thing: Any, *, format: str | None = None, stdin: BinaryIO | None = None) -> Solid:
    """Resolve ``thing`` into a ``Solid``, reading it if it is a file.

    Parameters
    ----------
    thing : str, os.PathLike, Shape, (n, 3, 3) array_like, (vertices, faces) pair, MeshSource, mesh object
        A shape spec (``"box:1,2,3"``) or a path (``"-"``: standard input); a shape object; an
        ``(n, 3, 3)`` array of triangle corners; a pair of an ``(m, 3)`` vertex array and an
        ``(n, 3)`` array of vertex indices (0-based); an already loaded mesh; or another
        library's mesh object, read by duck typing (neither library is imported): one with
        ``vertices`` and ``faces`` arrays (``trimesh.Trimesh``), or one with ``points`` and
        ``cells`` blocks of ``type`` and ``data`` (``meshio.Mesh``: its triangle, quad and
        polygon cells, or its tetrahedra), as p3d reads them from a file.
    format : str, optional
        Format name for a path, instead of guessing from content and extension.
    stdin : binary stream, optional
        What ``-`` reads; default ``sys.stdin.buffer``.

    Raises
    ------
    SpecError, InputError, UsageError
    """
    if isinstance(thing, MeshSource):
        return Solid(thing.where, mesh=thing)
    if isinstance(thing, os.PathLike):
        thing = os.fspath(thing)
    if isinstance(thing, str):
        shape = resolve_spec(thing)
        if shape is not None:
            return Solid(thing, shape=shape, warnings=tuple(spec_warnings(thing)))
        from p3d_cli.io import load_mesh

        return Solid(thing, mesh=load_mesh(thing, format, stdin=stdin))
    if is_shape(thing):
        return Solid(thing.spec(), shape=thing)
    if isinstance(thing, (tuple, list)) and len(thing) == 2:
        return Solid("<array>", mesh=indexed_mesh(*thing))
    if hasattr(thing, "vertices") and hasattr(thing, "faces"):      # trimesh.Trimesh and its kind
        where = f"<{type(thing).__name__}>"
        mesh = dataclasses.replace(indexed_mesh(thing.vertices, thing.faces, "trimesh"), where=where)
        return Solid(where, mesh=mesh)
    if hasattr(thing, "points") and hasattr(thing, "cells"):        # meshio.Mesh
        from p3d_cli.io.meshio_backend import mesh_object_source

        where = f"<{type(thing).__name__}>"
        return Solid(where, mesh=mesh_object_source(thing, where))
    if isinstance(thing, (np.ndarray, list)):
        return Solid("<array>", mesh=triangle_mesh(thing))
    raise UsageError("thing", f"cannot measure a {type(thing).__name__}",
                     "give a path, a shape spec or shape, an (n, 3, 3) triangle array, a "
                     "(vertices, faces) pair, or a mesh object with vertices and faces (trimesh) or "
                     "points and cells (meshio)")


def is_shape(thing: Any) -> TypeGuard[Shape]:
    """True for an instance of a registered shape class."""
    return isinstance(thing, tuple(SHAPES.values()))


def triangle_mesh(triangles) -> MeshSource:
    """A ``MeshSource`` over an ``(n, 3, 3)`` array of triangle corners (float32 kept as is)."""
    array = np.asarray(triangles)
    if array.ndim != 3 or array.shape[1:] != (3, 3) or not _is_real(array):
        raise UsageError("triangles", f"expected an (n, 3, 3) array of numbers, got shape {array.shape}",
                         "stack the corners as triangles[i, corner, axis]")
    dtype = "float32" if array.dtype == np.float32 else "float64"
    return array_source("array", array if dtype == "float32" else array.astype(np.float64), dtype)


def indexed_mesh(vertices, faces, format: str = "array") -> MeshSource:
    """A ``MeshSource`` over an ``(m, 3)`` vertex array and an ``(n, 3)`` index array (0-based)."""
    v, f = np.asarray(vertices), np.asarray(faces)
    if v.ndim != 2 or v.shape[1] != 3 or not _is_real(v):
        raise UsageError("vertices", f"expected an (m, 3) array of numbers, got shape {v.shape}",
                         "give one row x, y, z per vertex")
    if f.ndim != 2 or f.shape[1] != 3 or not np.issubdtype(f.dtype, np.integer):
        raise UsageError("faces", f"expected an (n, 3) array of integers, got shape {f.shape} of {f.dtype}",
                         "give one row of three vertex indices (from 0) per triangle")
    if len(f) and (f.min() < 0 or f.max() >= len(v)):
        bad = int(np.flatnonzero((f < 0).any(axis=1) | (f >= len(v)).any(axis=1))[0])
        raise InputError("<array>", f"face {bad} indexes a vertex outside 0..{len(v) - 1}",
                         "indices count from 0")
    dtype = "float32" if v.dtype == np.float32 else "float64"
    return indexed_source(format, v if dtype == "float32" else v.astype(np.float64), f.astype(np.intp), dtype)


def _is_real(array: np.ndarray) -> bool:
    return np.issubdtype(array.dtype, np.floating) or np.issubdtype(array.dtype, np.integer)


def resolve_spec(source: str) -> Shape | None:
    """The shape ``source`` names, or None for a path.

    Raises
    ------
    SpecError
        A malformed spec, or ``word:numbers`` text naming neither a shape nor an existing file.
    """
    shape = parse_spec(source)
    if shape is None and looks_like_spec(source) and ":" in source and not os.path.exists(source):
        name = source.split(":", 1)[0]
        raise SpecError(source, f"no shape named {name!r} and no such file",
                        "shapes are: " + ", ".join(SHAPES) + "; write ./" + source + " for a file")
    return shape


def spec_warnings(source: str) -> list[CodedWarning]:
    """A file named like a spec is shadowed by the spec; say so and how to reach it."""
    if os.path.exists(source):
        return [CodedWarning(f"{source!r} is read as a shape spec, not as the file of that name; "
                             f"write ./{source} for the file", "spec-shadows-file")]
    return []


def names_assembly_file(path) -> bool:
    """True for a text file with a top-level ``parts:`` line: an assembly (YAML, recognised by
    its content; ``p3d_cli.measure.assembly.parts``), told without importing the assembly modules."""

    path = os.fspath(path)
    if path == "-" or not os.path.isfile(path):
        return False
    try:
        with open(path, "rb") as f:
            head = f.read(1 << 14)
    except OSError:
        return False
    return b"\0" not in head and re.search(rb"^parts\s*:", head, re.MULTILINE) is not None
