"""Scene files read by trimesh's loaders (glTF, 3MF), as ``SceneObject`` lists.

trimesh (with lxml and networkx for 3MF: the ``formats`` extra) is the
maintained reader of these formats; it is imported here, on first use, so that runs on STL,
OBJ or PLY never pay for it. It is asked for the scene graph unprocessed (``process=False``:
no vertex merging, no removal of degenerate or duplicate faces), so p3d integrates the file's
own triangles. Only arrays leave this module; no trimesh object crosses the package boundary.
"""

from __future__ import annotations

import contextlib
import logging
from typing import Iterator

import numpy as np

from p3d_cli.errors import FormatError, P3DError
from p3d_cli.io.raw import RawInput
from p3d_cli.io.scene import SceneObject, require, unique_names


class _Collect(logging.Handler):
    """Keeps trimesh's log warnings (the library must not print; they become the source's)."""

    def __init__(self) -> None:
        super().__init__(logging.WARNING)
        self.lines: list[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.lines.append(record.getMessage())


@contextlib.contextmanager
def _captured_log() -> Iterator[_Collect]:
    logger = logging.getLogger("trimesh")
    handler = _Collect()
    logger.addHandler(handler)
    try:
        yield handler
    finally:
        logger.removeHandler(handler)


def load_scene(raw: RawInput, file_type: str, what: str, modules: tuple[str, ...] = ()):
    """``raw`` read by trimesh as a scene of ``file_type``, and trimesh's warnings.

    Parameters
    ----------
    modules : tuple of str
        The other packages the loader needs (``collada``, ``lxml``, ``networkx``), checked
        first so that a missing one is named rather than met as trimesh's own error.

    Raises
    ------
    MissingExtraError
        trimesh or a module it needs for this format is not installed.
    FormatError
        The loader cannot read the file.
    """
    trimesh = require("trimesh", raw.where, what)
    for module in modules:
        require(module, raw.where, what)
    with _captured_log() as log:
        try:
            scene = _unprocessed(trimesh, raw, file_type)
        except P3DError:
            raise
        except Exception as exc:  # noqa: BLE001 - a third-party parser on bad bytes raises anything
            detail = str(exc).strip().splitlines()[0][:120] if str(exc).strip() else type(exc).__name__
            raise FormatError(raw.where, f"cannot be read as {what} ({detail})",
                              "the file is corrupt or not in this format; export it again") from None
    return scene, tuple(f"{file_type}: {line}" for line in log.lines)


def _unprocessed(trimesh, raw: RawInput, file_type: str):
    """The scene as the file has it. ``trimesh.load_scene(..., process=False)`` does not pass
    ``process`` on to the meshes of a COLLADA or 3MF scene, which then merge vertices closer
    than 1e-8 (``Trimesh.process``); so the format's loader is called here, every mesh is
    marked unprocessed, and the scene is built from that."""
    from trimesh.exchange.load import mesh_loaders
    from trimesh.resolvers import FilePathResolver

    # A resolver by path, so that a .gltf finds its buffers (and a .dae its references) beside it.
    resolver = FilePathResolver(raw.path) if raw.path is not None else None
    # glTF's materials (textures: images to decode) play no part in the geometry.
    extra = {"skip_materials": True} if file_type in ("gltf", "glb") else {}
    with raw.open() as stream:
        loaded = mesh_loaders[file_type](file_obj=stream, file_type=file_type, resolver=resolver,
                                         metadata=None, process=False, **extra)
    if not isinstance(loaded, dict) or not isinstance(loaded.get("geometry"), dict):
        raise ValueError("the loader returned no scene")
    for mesh in loaded["geometry"].values():
        if isinstance(mesh, dict):
            mesh["process"] = False
    return trimesh.load_scene(loaded)


def scene_objects(scene, *, float32: bool = False, order: list[str] | None = None) -> tuple[list[SceneObject], int]:
    """Every mesh instance of a trimesh scene, with its whole transform (node names made
    unique), and the number of instances without faces (points, lines) left out.

    Parameters
    ----------
    float32 : bool
        The format stores coordinates as float32 (glTF): hand them on as float32 (trimesh
        widened them to float64 exactly), so that their precision is reported as stored.
    order : list of str, optional
        Node names in file order: trimesh walks the graph in its own order, and the parts
        are listed as the file lists them (names not found keep trimesh's order, after).
    """
    found = []
    skipped = 0
    for node in scene.graph.nodes_geometry:
        matrix, geometry_name = scene.graph[node]
        geometry = scene.geometry.get(geometry_name)
        faces = getattr(geometry, "faces", None)
        if geometry is None or faces is None or not len(faces):
            skipped += 1
            continue
        vertices = np.asarray(geometry.vertices)
        if float32:
            narrow = vertices.astype(np.float32)
            if np.array_equal(narrow, vertices):
                vertices = narrow
        found.append((str(node), vertices, np.asarray(faces), np.asarray(matrix, dtype=np.float64)))
    if order:
        rank = {name: i for i, name in reversed(list(enumerate(order)))}
        found.sort(key=lambda entry: rank.get(entry[0], len(rank)))
    names = unique_names([name for name, _, _, _ in found])
    return [SceneObject(n, v, f, m) for n, (_, v, f, m) in zip(names, found)], skipped


def skipped_note(skipped: int, kind: str) -> tuple[str, ...]:
    """The warning for instances left out because they hold no faces."""
    if not skipped:
        return ()
    return (f"{skipped} {kind} without faces (points or lines) hold no volume and are left out",)
