"""Writing meshes: binary STL, PLY, OBJ and OFF, each through ``p3d_cli.io.atomic``.

Every writer takes an indexed mesh (``vertices`` ``(m, 3)`` float32 or float64, ``faces``
``(n, 3)`` integer) and, for STL, may take the triangles themselves (``(n, 3, 3)``, the
corners exactly as stored, so that ``-0.0`` keeps its sign). Nothing is rounded that the
format can hold:

- **STL** is written binary, unless asked for ASCII (``ascii_stl``: what an ASCII STL repaired
  in place is written as, every coordinate as OBJ's are). Binary STL stores float32: float32
  coordinates are written as they are; float64 coordinates are written only when every one is
  a float32 value (otherwise ``OutputError``: PLY, OBJ and OFF keep float64). Each record's
  normal is the unit normal of its float32 corners (computed in float64, rounded once), its
  attribute 0.
- **PLY** is written binary little-endian with the coordinates' own type (``float`` for
  float32, ``double`` for float64) and ``uchar``-counted ``int`` face lists.
- **OBJ** and **OFF** are text: every coordinate is written as Python's ``repr`` of its
  float64 value (float32 widened exactly), the shortest text that reads back to the same
  bits, so a reader parsing float64 gets the very coordinates written.

The format comes from the record of ``p3d_cli.io.formats.FORMATS`` (its ``writer``): an
explicit name, or the path's extension.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import BinaryIO, Callable, Iterable

import numpy as np

from p3d_cli.errors import OutputError, UsageError
from p3d_cli.io.atomic import replacing

#: Faces or vertices formatted per text chunk (bounded temporaries on large meshes).
_CHUNK = 1 << 16

_STL_RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])


def writable_formats() -> tuple[str, ...]:
    """The format names p3d writes (records of ``FORMATS`` with a writer)."""
    from p3d_cli.io.formats import FORMATS

    return tuple(name for name, f in FORMATS.items() if f.writer)


def output_format(path: str | os.PathLike, override: str | None = None) -> str:
    """The format to write ``path`` in: ``override`` (a format name or alias), else the
    extension's.

    Raises
    ------
    UsageError
        The name or extension is not a format p3d writes.
    """
    from p3d_cli.io.formats import EXTENSIONS, FORMATS

    names = ", ".join(writable_formats())
    if override:
        name = override.lower()
        for f in FORMATS.values():
            if name == f.name or name in f.aliases:
                if f.writer:
                    return f.name
                break
        raise UsageError("output_format", f"p3d does not write {override!r}", f"write one of {names}")
    ext = os.path.splitext(os.fspath(path))[1].lower()
    name = EXTENSIONS.get(ext)
    if name is None or not FORMATS[name].writer:
        what = f"extension {ext!r}" if ext else "a name without an extension"
        raise UsageError(os.fspath(path), f"cannot write a mesh to {what}",
                         f"name the output .stl, .ply, .obj or .off, or give an output format ({names})")
    return name


def write_mesh(path: str | os.PathLike, vertices: np.ndarray | None, faces: np.ndarray | None, *,
               triangles: np.ndarray | None = None, format: str | None = None,
               inputs: Iterable[str | os.PathLike] = (), in_place: bool = False,
               what: str = "the mesh", ascii_stl: bool = False) -> Path:
    """Write an indexed mesh to ``path`` (replaced whole, or left as it was on any error).

    Parameters
    ----------
    vertices : (m, 3) float32 or float64, or None
    faces : (n, 3) int, or None
        0-based indices into ``vertices`` (both may be None for STL when ``triangles`` is given).
    triangles : (n, 3, 3), optional
        ``vertices[faces]`` with each corner as stored (the sign of a zero kept); used by STL.
    format : str, optional
        A format name (``stl``, ``ply``, ``obj``, ``off``); default: the extension's.
    inputs, in_place, what
        As for ``p3d_cli.io.atomic.replacing``: writing over an input is refused unless
        ``in_place``.
    ascii_stl : bool
        Write STL as text (float64 coordinates kept exactly) rather than binary.

    Returns
    -------
    Path
        The real path written.

    Raises
    ------
    OutputError, UsageError
    """
    from p3d_cli.io.formats import FORMATS

    name = output_format(path, format)
    writer: Callable = write_stl_ascii if name == "stl" and ascii_stl else globals()[FORMATS[name].writer or ""]
    if vertices is None or faces is None:
        if name != "stl" or triangles is None:
            raise UsageError("vertices, faces", "not given", "give the mesh's vertices and faces")
    else:
        vertices = np.asarray(vertices)
        faces = np.asarray(faces, dtype=np.int64).reshape(-1, 3)
        if vertices.dtype not in (np.float32, np.float64):
            vertices = vertices.astype(np.float64)
        if triangles is None and name == "stl":
            triangles = vertices[faces]
    if not ascii_stl:
        _refuse_rounding(path, name, triangles if name == "stl" else vertices)
    with replacing(path, inputs=inputs, in_place=in_place, what=what) as f:
        writer(f, vertices, faces, triangles)
    return Path(os.path.realpath(path))


def _refuse_rounding(path, name: str, coordinates: np.ndarray) -> None:
    """Binary STL holds float32: refuse float64 coordinates it would round."""
    if name != "stl" or coordinates.dtype == np.float32:
        return
    narrowed = coordinates.astype(np.float32)
    lost = int(np.count_nonzero(narrowed.astype(np.float64) != coordinates))
    if lost:
        raise OutputError(os.fspath(path), f"binary STL stores float32, and {lost} of the float64 coordinates "
                          "are not float32 values (they would be rounded)",
                          "write .ply, .obj or .off, which keep float64")


def write_stl(f: BinaryIO, vertices: np.ndarray, faces: np.ndarray, triangles: np.ndarray) -> None:
    """Binary STL: an 80-byte header, the count, one 50-byte record per face."""
    corners = np.asarray(triangles).astype(np.float32, copy=False)
    f.write(b"binary STL written by p3d repair".ljust(80, b" "))
    f.write(np.uint32(len(corners)).tobytes())
    for start in range(0, len(corners), _CHUNK):
        part = corners[start:start + _CHUNK]
        record = np.zeros(len(part), _STL_RECORD)
        record["corners"] = part
        record["normal"] = _unit_normals(part)
        f.write(record.tobytes())


def write_stl_ascii(f: BinaryIO, vertices, faces, triangles: np.ndarray) -> None:
    """ASCII STL: one ``solid``, each facet's unit normal and its corners as ``repr`` floats."""
    corners = np.asarray(triangles)
    f.write(b"solid repaired\n")
    for start in range(0, len(corners), _CHUNK):
        part = corners[start:start + _CHUNK]
        normals = _unit_normals(part.astype(np.float32)).astype(np.float64).tolist()
        text = []
        for normal, tri in zip(normals, part.astype(np.float64).tolist()):
            text.append("facet normal {!r} {!r} {!r}\n outer loop\n".format(*normal))
            text.extend("  vertex {!r} {!r} {!r}\n".format(*p) for p in tri)
            text.append(" endloop\nendfacet\n")
        f.write("".join(text).encode("ascii"))
    f.write(b"endsolid repaired\n")


def _unit_normals(corners: np.ndarray) -> np.ndarray:
    """Unit normals ``(k, 3)`` float32 of float32 triangles (zero for a zero-area face)."""
    wide = corners.astype(np.float64)
    normal = np.cross(wide[:, 1] - wide[:, 0], wide[:, 2] - wide[:, 0])
    length = np.sqrt((normal * normal).sum(axis=1))
    length[length == 0] = 1.0
    return (normal / length[:, None]).astype(np.float32)


def write_ply(f: BinaryIO, vertices: np.ndarray, faces: np.ndarray, triangles=None) -> None:
    """Binary little-endian PLY with the coordinates' own type (``float`` or ``double``)."""
    if len(vertices) >= 2**31:
        raise OutputError("<output>", "PLY face lists hold int indices, and the mesh has 2^31 vertices or more",
                          "split the mesh")
    kind = "float" if vertices.dtype == np.float32 else "double"
    header = (f"ply\nformat binary_little_endian 1.0\ncomment written by p3d repair\n"
              f"element vertex {len(vertices)}\nproperty {kind} x\nproperty {kind} y\nproperty {kind} z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    f.write(header.encode("ascii"))
    f.write(np.ascontiguousarray(vertices, dtype="<f4" if kind == "float" else "<f8").tobytes())
    record = np.dtype([("k", "u1"), ("ids", "<i4", (3,))])
    for start in range(0, len(faces), _CHUNK):
        part = faces[start:start + _CHUNK]
        out = np.empty(len(part), record)
        out["k"] = 3
        out["ids"] = part
        f.write(out.tobytes())


def _coordinate_lines(prefix: str, vertices: np.ndarray):
    """``prefix x y z`` lines, each coordinate as ``repr`` of its float64 value."""
    for start in range(0, len(vertices), _CHUNK):
        rows = vertices[start:start + _CHUNK].astype(np.float64).tolist()
        yield "".join(f"{prefix}{x!r} {y!r} {z!r}\n" for x, y, z in rows).encode("ascii")


def _face_lines(prefix: str, faces: np.ndarray, base: int):
    for start in range(0, len(faces), _CHUNK):
        rows = (faces[start:start + _CHUNK] + base).tolist()
        yield "".join(f"{prefix}{a} {b} {c}\n" for a, b, c in rows).encode("ascii")


def write_obj(f: BinaryIO, vertices: np.ndarray, faces: np.ndarray, triangles=None) -> None:
    """Wavefront OBJ: ``v`` lines, then ``f`` lines with 1-based indices."""
    f.write(b"# written by p3d repair\n")
    for chunk in _coordinate_lines("v ", vertices):
        f.write(chunk)
    for chunk in _face_lines("f ", faces, 1):
        f.write(chunk)


def write_off(f: BinaryIO, vertices: np.ndarray, faces: np.ndarray, triangles=None) -> None:
    """OFF: the counts, the vertex lines, then ``3 a b c`` face lines (0-based)."""
    f.write(f"OFF\n# written by p3d repair\n{len(vertices)} {len(faces)} 0\n".encode("ascii"))
    for chunk in _coordinate_lines("", vertices):
        f.write(chunk)
    for chunk in _face_lines("3 ", faces, 0):
        f.write(chunk)
