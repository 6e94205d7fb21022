"""Files that hold a scene: named objects, each placed by its node transform, in declared units.

glTF, 3MF, COLLADA (DAE) and AMF files describe a scene graph: meshes instanced by nodes whose
transforms compose down the tree, and a length unit for the whole file. Their readers
(``p3d_cli.io.dae``, ``p3d_cli.io.amf``, ``p3d_cli.io.gltf``, ``p3d_cli.io.threemf``) hand
this module a list of ``SceneObject`` (one per mesh instance: a mesh's vertices and all its
faces, whatever their materials, and the instance's whole transform) and the file's unit in
metres; ``scene_source`` turns them into one ``MeshSource``:

- every object's vertices are carried through its transform as its blocks are read (float64,
  one matrix product, so that many instances of one mesh hold the mesh once; an
  identity transform leaves the stored numbers as they are, float32 included), and faces of an
  object whose transform mirrors (negative determinant) are reversed, as glTF 2.0 (§3.7.4,
  "the determinant of the node's global transform defines the winding order") and 3MF (§4.1)
  say, so that a mirrored solid stays outward;
- nothing is merged, repaired, dropped or flipped: the results are the exact integrals of the
  file's own triangles, placed, and a part is a placed mesh, never a material group;
- the unit becomes ``MeshSource.length_unit`` (a key of ``p3d_cli.units.LENGTHS``): a unit of
  that table keeps the coordinates as stored, any other (DAE ``meter="0.5"``, 3MF ``micron``)
  is folded into the transforms so that the coordinates are in metres;
- a file of several objects lists them in ``MeshSource.objects``, which ``p3d_cli.measure``
  measures as an assembly of those parts.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Callable, Iterator

import numpy as np

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.source import BLOCK, MeshSource, indexed_source
from p3d_cli.warning_codes import CodedWarning

#: Relative tolerance for recognising a declared unit as one of ``LENGTHS`` (``0.0254`` as
#: written in a file is the inch).
_UNIT_RTOL = 1e-9


@dataclass(frozen=True)
class SceneObject:
    """One mesh instance of a scene.

    Attributes
    ----------
    name : str
        Unique within the file (node or object name).
    vertices : (m, 3) float32 or float64
        As stored in the file.
    faces : (n, 3) integer
    transform : (4, 4) float64
        The object's whole transform (the product down the node tree), in the file's unit.
    """

    name: str
    vertices: np.ndarray
    faces: np.ndarray
    transform: np.ndarray


def unit_for(metres: float) -> tuple[str, float]:
    """The ``LENGTHS`` key for a declared unit of ``metres`` metres, and the factor still to
    apply to the coordinates (1.0 when the unit is in the table; else the coordinates are
    converted to metres)."""
    from p3d_cli.units import LENGTHS

    for key, value in LENGTHS.items():
        if abs(metres - value) <= _UNIT_RTOL * value:
            return key, 1.0
    return "m", float(metres)


def check_object(obj: SceneObject, where: str) -> None:
    """Refuse an object whose arrays are not a mesh or whose faces name a missing vertex.

    Raises
    ------
    FormatError
    """
    faces = np.asarray(obj.faces)
    vertices = np.asarray(obj.vertices)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise FormatError(f"{where}#{obj.name}", f"vertices of shape {vertices.shape} and faces of shape "
                          f"{faces.shape} (expected m x 3 and n x 3)", "the file is corrupt; export it again")
    if len(faces) and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise FormatError(f"{where}#{obj.name}", f"a face refers to a vertex outside 0..{len(vertices) - 1}",
                          "the file is corrupt; export it again")


def placement_of(obj: SceneObject, factor: float, where: str) -> np.ndarray | None:
    """``obj``'s whole transform with the unit ``factor`` folded in, or None for the identity
    (the stored numbers are then integrated as they are).

    Raises
    ------
    FormatError
        Not a finite 4 x 4 matrix.
    """
    matrix = np.asarray(obj.transform, dtype=np.float64)
    if matrix.shape != (4, 4) or not np.all(np.isfinite(matrix)):
        raise FormatError(f"{where}#{obj.name}", "the object's transform is not a finite 4 x 4 matrix",
                          "the file is corrupt; export it again")
    if factor != 1.0:
        matrix = np.diag([factor, factor, factor, 1.0]) @ matrix
    return None if np.array_equal(matrix, np.eye(4)) else matrix


def placed(obj: SceneObject, factor: float, where: str) -> tuple[np.ndarray, np.ndarray, bool]:
    """``obj``'s vertices through its transform (and ``factor``), its faces (reversed under a
    mirroring transform), and whether the stored numbers were kept as they are."""
    check_object(obj, where)
    return _place(np.asarray(obj.vertices), np.asarray(obj.faces), placement_of(obj, factor, where))


def _place(vertices: np.ndarray, faces: np.ndarray, matrix: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, bool]:
    if matrix is None:
        return vertices, faces, True
    linear = matrix[:3, :3]
    out = vertices.astype(np.float64) @ linear.T + matrix[:3, 3]
    if np.linalg.det(linear) < 0:
        faces = faces[:, ::-1]
    return out, faces, False


def _stored_dtype(vertices: np.ndarray) -> str:
    return "float32" if vertices.dtype == np.float32 else "float64"


def object_source(fmt: str, where: str, vertices: np.ndarray, faces: np.ndarray, dtype: str,
                  unit: str, matrix: np.ndarray | None = None) -> MeshSource:
    """A ``MeshSource`` over one object, placed by ``matrix`` (when given) as its blocks are
    read: a scene of many instances of one mesh holds the mesh once, never its copies. An
    object left as stored is an indexed mesh (``indexed_source``: the same blocks, and the
    kernels read its vertices and faces without gathering them)."""
    vertices = vertices if vertices.dtype in (np.float32, np.float64) else vertices.astype(np.float64)
    faces = faces if faces.dtype in (np.int32, np.intp) else faces.astype(np.intp)
    if matrix is None:
        return dataclasses.replace(indexed_source(fmt, vertices, faces, dtype), where=where, length_unit=unit)

    def read_blocks() -> Iterator[np.ndarray]:
        points, corners, _ = _place(vertices, faces, matrix)
        for start in range(0, len(corners), BLOCK):
            yield points[corners[start:start + BLOCK]]

    return MeshSource(fmt, int(len(faces)), dtype, read_blocks, where=where, length_unit=unit)


def scene_source(fmt: str, where: str, objects: list[SceneObject], metres: float, kind: str,
                 warnings: tuple[CodedWarning, ...] = ()) -> MeshSource:
    """One ``MeshSource`` for a scene's objects (see the module's description).

    Parameters
    ----------
    fmt : str
        ``MeshSource.format`` (``gltf``, ``3mf``, ``dae``, ``amf``).
    where : str
        The input's name; an object's is ``where#name``.
    objects : list of SceneObject
        One per mesh instance: a mesh is one object whatever its materials or primitives.
    metres : float
        The file's length unit in metres.
    kind : str
        What the file calls its objects (``nodes``, ``build items``), for the record.

    Raises
    ------
    FormatError
        An object's faces name a missing vertex, or its transform is not finite.
    InputError
        No object with faces.
    """
    unit, factor = unit_for(metres)
    parts = []
    checked: set[int] = set()
    for obj in objects:
        if not len(obj.faces):
            continue
        if id(obj.faces) not in checked:     # instances share their mesh's arrays: check it once
            check_object(obj, where)
            checked.add(id(obj.faces))
        matrix = placement_of(obj, factor, where)
        vertices = np.asarray(obj.vertices)
        dtype = _stored_dtype(vertices) if matrix is None else "float64"
        parts.append((obj.name, object_source(fmt, f"{where}#{obj.name}", vertices, np.asarray(obj.faces), dtype,
                                              unit, matrix)))
    if not parts:
        raise InputError(where, "the file holds no triangles (no mesh object with faces)",
                         "export the model with its meshes")
    dtypes = {source.coordinate_dtype for _, source in parts}

    def every_part() -> Iterator[np.ndarray]:
        for _, source in parts:
            yield from source.read_blocks()

    listed = tuple(parts) if len(parts) > 1 else ()
    # One object is read as its own source is (an unplaced one by the kernels' indexed road).
    read_blocks, indexed = (every_part, None) if listed else (parts[0][1].read_blocks, parts[0][1].indexed)
    return MeshSource(fmt, sum(s.face_count for _, s in parts), "float32" if dtypes == {"float32"} else "float64",
                      read_blocks, None, tuple(warnings), where, length_unit=unit, objects=listed,
                      object_kind=kind if listed else "", indexed=indexed)


def instance_totals(where: str, roots: list, children: Callable[[Any], list], own: Callable[[Any], tuple[int, int]],
                    what: str) -> tuple[int, int]:
    """The mesh instances and triangles a scene graph places from ``roots``, counted without
    placing anything: each graph node's ``own(node)`` (instances, triangles) plus its
    ``children(node)``'s totals (a child reached twice counts twice, as it is placed twice).
    Every node is computed once, by an iterative post-order walk (no recursion a deep file can
    exhaust). Python's integers do not overflow, so a graph of 2^100 instances is counted too.

    Raises
    ------
    FormatError
        A node reaches itself (``what`` names the kind of graph node in the message).
    """
    totals: dict[int, tuple[int, int]] = {}
    entered: set[int] = set()
    result = [0, 0]
    for root in roots:
        stack = [(root, False)]
        while stack:
            node, finished = stack.pop()
            key = id(node)
            if finished:
                count, faces = own(node)
                for child in children(node):
                    sub = totals[id(child)]
                    count, faces = count + sub[0], faces + sub[1]
                totals[key] = (count, faces)
                continue
            if key in totals:
                continue
            if key in entered:      # entered and not finished: an ancestor of itself
                raise FormatError(where, f"{what} {_label(node)} contains itself (a cycle of instances)",
                                  "the file is corrupt; export it again")
            entered.add(key)
            stack.append((node, True))
            for child in children(node):
                if id(child) in entered and id(child) not in totals:
                    raise FormatError(where, f"{what} {_label(child)} contains itself (a cycle of instances)",
                                      "the file is corrupt; export it again")
                if id(child) not in totals:
                    stack.append((child, False))
        result[0] += totals[id(root)][0]
        result[1] += totals[id(root)][1]
    return result[0], result[1]


def _label(node) -> str:
    get = getattr(node, "get", None)
    name = (get("id") or get("name")) if get is not None else None
    return repr(name) if name else "(unnamed)"


def unique_names(names: list[str]) -> list[str]:
    """``names`` made unique by ``-2``, ``-3``... suffixes on repeats (and ``object`` for blanks)."""
    seen: dict[str, int] = {}
    out = []
    for name in names:
        name = name or "object"
        count = seen.get(name, 0) + 1
        seen[name] = count
        out.append(name if count == 1 else f"{name}-{count}")
    return out
