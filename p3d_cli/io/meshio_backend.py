"""Every other format meshio reads (VTU, VTK, Gmsh, Abaqus, Medit, XDMF, ...).

Surface cells (``triangle``, ``quad``, ``polygon``) become triangles, polygons split as fans
from their first vertex. A volume mesh with ``tetra`` cells is returned as tetrahedra, whose
integrals are exact, instead of its boundary. meshio is imported only here, inside the
functions, so ``import p3d_cli.io`` stays fast and a missing meshio fails only when used.

meshio's own ``meshio.read`` is not used: when a reader fails it prints the error and calls
``sys.exit(1)`` (meshio 5.3, ``_helpers._read_file``), which a library must never do. The
reader for the chosen format is called directly instead, and its errors become FormatError.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import os
import re
import tempfile

import numpy as np

from p3d_cli.errors import FormatError, InputError, MissingExtraError, UsageError
from p3d_cli.io.polygons import fan_triangles
from p3d_cli.io.raw import RawInput
from p3d_cli.io.source import MeshSource, indexed_source
from p3d_cli.warning_codes import CodedWarning

#: Formats p3d reads with its own loaders; meshio is never asked about these.
OWN = {"stl", "obj", "ply", "off"}
#: Where one extension maps to several meshio readers, the one meant (``.msh``: Gmsh files
#: are far more common than ANSYS ones).
_PREFERRED = {".msh": "gmsh"}
#: Volume cells p3d cannot integrate yet; refusing beats silently ignoring their mass.
_OTHER_VOLUME = ("hexahedron", "wedge", "pyramid", "tetra10", "hexahedron20", "hexahedron27",
                 "wedge15", "pyramid13", "pyramid14")
_SURFACE = ("triangle", "quad", "polygon")


def _helpers():
    try:
        from meshio import _helpers
    except ImportError:
        return None
    return _helpers


def _require(where: str):
    helpers = _helpers()
    if helpers is None:
        raise MissingExtraError(where, "reading this format needs the meshio package, which is not installed",
                                "install it: pip install meshio")
    return helpers


def knows_extension(ext: str) -> bool:
    """True when meshio has a reader for files ending in ``ext`` (``".vtu"``), other than the
    formats p3d reads itself."""
    helpers = _helpers()
    if helpers is None or not ext:
        return False
    names = helpers.extension_to_filetypes.get(ext.lower(), [])
    return any(n in helpers.reader_map and n not in OWN for n in names)


def knows_format(name: str) -> bool:
    """True when ``name`` is a meshio reader name (``"vtu"``, ``"gmsh"``) p3d does not own."""
    helpers = _helpers()
    return helpers is not None and name in helpers.reader_map and name not in OWN


def format_for_extension(ext: str) -> str:
    """The meshio format name used for ``ext``.

    Raises
    ------
    KeyError
        meshio has no reader for ``ext``.
    """
    ext = ext.lower()
    helpers = _helpers()
    if helpers is None:
        raise KeyError(ext)
    names = [n for n in helpers.extension_to_filetypes.get(ext, []) if n in helpers.reader_map and n not in OWN]
    if not names:
        raise KeyError(ext)
    return _PREFERRED.get(ext, names[0]) if _PREFERRED.get(ext) in names else names[0]


def _extension_for(helpers, name: str) -> str:
    for ext, names in helpers.extension_to_filetypes.items():
        if name in names:
            return ext
    return ""


#: Declared counts in the formats whose readers allocate by them before reading: the regular
#: expression finding each count and the fewest bytes one item takes in the file (a point is at
#: least ``0 0 0`` and a newline in text, 12 bytes in binary; a Gmsh node adds its tag).
_COUNTS = {
    "vtk": [(re.compile(rb"^[ \t]*POINTS[ \t]+([0-9]+)", re.M), 6, "points"),
            (re.compile(rb"^[ \t]*CELLS[ \t]+[0-9]+[ \t]+([0-9]+)", re.M), 2, "cell index values")],
    "gmsh": [(re.compile(rb"^\$Nodes[ \t]*\r?\n[ \t]*([0-9]+)[ \t]*\r?$", re.M), 8, "nodes"),
             (re.compile(rb"^\$Nodes[ \t]*\r?\n[ \t]*[0-9]+[ \t]+([0-9]+)", re.M), 8, "nodes"),
             (re.compile(rb"^\$Elements[ \t]*\r?\n[ \t]*([0-9]+)[ \t]*\r?$", re.M), 4, "elements"),
             (re.compile(rb"^\$Elements[ \t]*\r?\n[ \t]*[0-9]+[ \t]+([0-9]+)", re.M), 4, "elements")],
}


def _check_declared_counts(raw: RawInput, name: str) -> None:
    """Refuse a file whose declared counts need more bytes than it has, before meshio allocates
    arrays of that size (a VTK file declaring 1e11 points asked numpy for 2 TiB)."""
    patterns = _COUNTS.get(name)
    if not patterns:
        return
    data = raw.read_all()
    for pattern, least, what in patterns:
        for found in pattern.finditer(data):
            count = int(found.group(1))
            if count * least > raw.size:
                raise FormatError(raw.where, f"meshio could not read it as {name}: the file declares {count} {what} "
                                  f"(at least {count * least} bytes) but has {raw.size} bytes",
                                  "the file is truncated or corrupt; export it again")


def load(raw: RawInput, name: str | None = None) -> MeshSource:
    """Read ``raw`` with meshio's reader for format ``name`` (default: from the extension).

    Returns
    -------
    MeshSource
        ``format="meshio:<name>"``: tetrahedra when the file has ``tetra`` cells, else its
        triangle, quad and polygon cells as triangles.

    Raises
    ------
    MissingExtraError
        meshio is not installed.
    FormatError
        meshio cannot read the file, or it holds volume cells other than tetrahedra.
    InputError
        No surface or tetrahedral cells.
    """
    helpers = _require(raw.where)
    if name is None:
        try:
            name = format_for_extension(os.path.splitext(raw.path or "")[1])
        except KeyError:
            raise UsageError(raw.where, "meshio has no reader for this extension",
                             "give --format with a meshio format name") from None
    reader = helpers.reader_map.get(name)
    if reader is None or name in OWN:
        raise UsageError(raw.where, f"{name!r} is not a meshio format p3d reads through meshio",
                         "give --format with a meshio format name such as vtu or gmsh")
    # meshio's readers print warnings to stderr themselves (through rich); a library must not
    # print, so they are captured and handed back as the source's warnings.
    _check_declared_counts(raw, name)
    captured = io.StringIO()
    try:
        with contextlib.redirect_stderr(captured):
            if raw.data is None:
                mesh = reader(raw.path)
            else:
                mesh = _read_stdin(raw, helpers, reader, name)
    except UsageError:
        raise
    except MemoryError:
        raise FormatError(raw.where, f"meshio ran out of memory reading it as {name} (the file declares more "
                          "points or cells than it holds, or is too large)",
                          "the file is corrupt or not in this format; check --format or export it again") from None
    except Exception as exc:  # noqa: BLE001 - any failure of meshio's reader on these bytes
        # Besides its own ReadError, meshio's readers raise whatever their parsing meets on
        # input that is not what they expect: ValueError, KeyError, IndexError, struct.error,
        # EOFError, XML ParseError, zlib.error, and TypeError/AssertionError/AttributeError on
        # files that are XML or text of another kind (a non-mesh .xml or .dat).
        detail = str(exc).strip().splitlines()[0][:120] if str(exc).strip() else type(exc).__name__
        raise FormatError(raw.where, f"meshio could not read it as {name} ({detail})",
                          "the file is corrupt or not in this format; check --format or export it again") from None
    notes = tuple(CodedWarning("meshio: " + line.strip().removeprefix("Warning:").strip(), "reader")
                  for line in captured.getvalue().splitlines() if line.strip())
    return _source(raw.where, name, mesh, notes)


def _read_stdin(raw: RawInput, helpers, reader, name: str):
    if name == "tetgen":
        raise UsageError(raw.where, "tetgen meshes are two files (.node and .ele) and cannot come from stdin",
                         "pass the .ele or .node path")
    # meshio readers want a file name (several pick their parser by the extension).
    handle, path = tempfile.mkstemp(suffix=_extension_for(helpers, name), prefix="p3d-stdin-")
    try:
        with os.fdopen(handle, "wb") as f:
            f.write(raw.data)
        return reader(path)
    finally:
        os.unlink(path)


def mesh_object_source(mesh, where: str) -> MeshSource:
    """A ``MeshSource`` over a ``meshio.Mesh`` already in memory, read as a file of it is
    (format ``meshio``; by its ``points`` and ``cells``: meshio is not imported).

    Raises
    ------
    FormatError, InputError
        As for a file: cells p3d does not integrate, indices out of range, no faces.
    """
    source = _source(where, "", mesh)
    return dataclasses.replace(source, format="meshio", where=where)


def _source(where: str, name: str, mesh, notes=()) -> MeshSource:
    fmt = "meshio:" + name
    points = np.asarray(mesh.points)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise FormatError(where, f"points of shape {points.shape} (expected n x 3)", "export the mesh again")
    dtype = "float32" if points.dtype == np.float32 else "float64"
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points), dtype=points.dtype)])
    blocks = [(block.type, np.asarray(block.data)) for block in mesh.cells]
    other = sorted({t for t, d in blocks if t in _OTHER_VOLUME and len(d)})
    tetra = [d for t, d in blocks if t == "tetra" and len(d)]
    if other:
        raise FormatError(where, f"the mesh holds {', '.join(other)} cells, which p3d does not integrate",
                          "convert the volume mesh to linear tetrahedra, or export its boundary surface")
    if tetra:
        cells = np.concatenate(tetra).astype(np.int64)
        _check_indices(where, cells, len(points), "tetra")
        tets = points[cells].astype(np.float64)
        surface = {t: len(d) for t, d in blocks if t in _SURFACE and len(d)}
        if surface:
            # Volume meshes often carry their boundary (or named patches) as surface cells too:
            # adding them would count nothing (they hold no volume) but say which was measured.
            held = ", ".join(f"{n} {t}" for t, n in sorted(surface.items()))
            notes = notes + (CodedWarning(f"the mesh holds {len(tets)} tetrahedra and surface cells ({held}): the "
                                          "tetrahedra were measured, the surface cells were not", "reader"),)
        return MeshSource(fmt, len(tets), dtype, lambda: iter(()), tets, notes)
    triangles = []
    for kind, data in blocks:
        if kind not in _SURFACE or not len(data):
            continue
        data = data.astype(np.int64).reshape(len(data), -1)
        _check_indices(where, data, len(points), kind)
        triangles.append(fan_triangles(data.reshape(-1), np.full(len(data), data.shape[1])))
    if not triangles:
        kinds = ", ".join(sorted({t for t, _ in blocks})) or "none"
        raise InputError(where, f"no faces (no triangle, quad, polygon or tetra cells; cells found: {kinds})",
                         "export the mesh with its surface or tetrahedra")
    faces = np.concatenate(triangles)
    if points.dtype not in (np.float32, np.float64):
        points = points.astype(np.float64)
    return indexed_source(fmt, points, faces, dtype, notes)


def _check_indices(where: str, cells: np.ndarray, count: int, kind: str) -> None:
    if cells.size and (cells.min() < 0 or cells.max() >= count):
        bad = cells[(cells < 0) | (cells >= count)][0]
        raise FormatError(where, f"a {kind} cell refers to point {int(bad)}, but there are {count} points",
                          "the file is corrupt; export it again")


__all__ = ["knows_extension", "knows_format", "format_for_extension", "load"]
