"""What every loader returns: ``MeshSource``, triangles (or tetrahedra) as plain arrays."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator

import numpy as np

from p3d_cli.errors import InputError
from p3d_cli.warning_codes import CodedWarning

#: Triangles handed to the integrals per block: large enough that numpy's per-call overhead
#: vanishes, small enough that a block's float64 columns (~1 MB) and the integrals' temporaries
#: stay in cache between the dozens of passes over them. Measured on a 1M-triangle STL: 16k
#: takes 25% less CPU than 64k, and 8k no less than 16k.
BLOCK = 1 << 14


@dataclass(frozen=True)
class MeshSource:
    """A loaded input, as triangles in blocks or as tetrahedra.

    Attributes
    ----------
    format : str
        ``stl-binary``, ``stl-ascii``, ``obj``, ``ply``, ``off`` or ``meshio:<name>``.
    face_count : int
        Number of triangles (polygons already split into fans) or tetrahedra.
    coordinate_dtype : str
        Precision of the coordinates as stored: ``float32`` or ``float64``.
    read_blocks : callable
        Returns an iterator over ``(k, 3, 3)`` arrays (float32 or float64) of triangle corners,
        in file order. Calling it again reads again (streams may read once only).
    tetrahedra : (n, 4, 3) float64 or None
        For volume meshes: the tetrahedra, whose integrals are used directly.
    warnings : tuple of CodedWarning
        Things the loader noticed that the user should hear about (trailing bytes, ...), each
        with its code (``p3d_cli.warning_codes``).
    where : str
        The input's name in messages: its path, ``<stdin>``, or ``<array>`` for arrays given
        from Python (set by ``p3d_cli.io.load_mesh``).
    length_unit : str or None
        The length unit the file declares for its coordinates (a key of
        ``p3d_cli.units.LENGTHS``: glTF, 3MF, DAE and AMF say theirs); None when it says none.
    objects : tuple of (str, MeshSource)
        For a file of several objects (scene nodes, build items), each one by name, already
        placed; the source itself yields all of them. Empty for a single object.
    object_kind : str
        What the file calls those objects (``nodes``, ``build items``), for the record.
    indexed : tuple or None
        For an indexed mesh (``indexed_source``): its ``(vertices, face pieces, reader)``, so
        that a reader of the indices (the compiled kernels) need not gather
        ``vertices[faces]``. ``reader`` is the ``read_blocks`` they stand for: a copy with
        other blocks (placed, projected, replaced) no longer counts as indexed
        (``indexed_arrays``), whoever makes it.
    """

    format: str
    face_count: int
    coordinate_dtype: str
    read_blocks: Callable[[], Iterator[np.ndarray]]
    tetrahedra: np.ndarray | None = None
    warnings: tuple[CodedWarning, ...] = field(default_factory=tuple)
    where: str = "<array>"
    length_unit: str | None = None
    objects: tuple[tuple[str, "MeshSource"], ...] = field(default_factory=tuple)
    object_kind: str = ""
    indexed: tuple | None = None

    def indexed_arrays(self) -> tuple[np.ndarray, tuple[np.ndarray, ...]] | None:
        """``(vertices, face pieces)`` while ``read_blocks`` is still the indexed mesh's own;
        None otherwise (not indexed, or a copy whose blocks differ)."""
        if self.indexed is None or self.indexed[2] is not self.read_blocks:
            return None
        return self.indexed[0], self.indexed[1]

    def index_blocks(self) -> Iterator[tuple[np.ndarray, np.ndarray]]:
        """``(vertices, faces)`` of every block of an indexed mesh: ``vertices[faces]`` is
        the block ``read_blocks`` yields (``indexed_arrays`` must not be None)."""
        arrays = self.indexed_arrays()
        if arrays is None:
            raise ValueError("index_blocks of a source whose blocks are not its indexed mesh's")
        vertices, pieces = arrays
        for block in _blocks_of(list(pieces), BLOCK):
            yield vertices, block

    def _repr_png_(self) -> bytes:
        """In a notebook: a picture of the mesh (``p3d_cli.render``)."""
        from p3d_cli.render.notebook import png_of

        return png_of(self)

    def triangles(self) -> np.ndarray:
        """All triangles in one ``(n, 3, 3)`` array (for callers that need them at once)."""
        blocks = list(self.read_blocks())
        if not blocks:
            return np.zeros((0, 3, 3))
        return np.concatenate(blocks) if len(blocks) > 1 else blocks[0]

    def finite_blocks(self) -> Iterator[np.ndarray]:
        """``read_blocks()``, refusing the first NaN or infinite coordinate (with its face index).

        Raises
        ------
        InputError
        """
        seen = 0
        for block in self.read_blocks():
            bad = first_nonfinite(block)
            if bad is not None:
                raise nonfinite_error(self.where, seen + bad)
            seen += len(block)
            yield block


def first_nonfinite(cells: np.ndarray) -> int | None:
    """Index of the first cell (triangle or tetrahedron, ``(n, k, 3)``) with a NaN or infinite
    coordinate, or None when all are finite."""
    finite = np.isfinite(cells).reshape(len(cells), -1).all(axis=1)
    return None if finite.all() else int(np.flatnonzero(~finite)[0])


def nonfinite_error(where: str, index: int, cell: str = "face") -> InputError:
    """The one message for a NaN or infinite coordinate in cell ``index``."""
    return InputError(where, f"{cell} {index} has a NaN or infinite coordinate", "repair or re-export the mesh")


def indexed_source(fmt: str, vertices: np.ndarray, faces, dtype: str,
                   warnings: tuple[CodedWarning, ...] = ()) -> MeshSource:
    """A ``MeshSource`` over an indexed mesh, yielding ``vertices[faces]`` block by block.

    Parameters
    ----------
    vertices : (m, 3) float32 or float64
    faces : (n, 3) integer array, or a list of such arrays (one face list in pieces, as a
        chunked reader makes them: the blocks are the same as for the pieces joined)
        Already validated to lie in ``[0, m)``.
    """
    pieces = list(faces) if isinstance(faces, list) else [faces]

    def read_blocks() -> Iterator[np.ndarray]:
        for block in _blocks_of(pieces, BLOCK):
            yield vertices[block]

    return MeshSource(fmt, sum(len(piece) for piece in pieces), dtype, read_blocks, None, tuple(warnings),
                      indexed=(vertices, tuple(pieces), read_blocks))


def _blocks_of(pieces: list[np.ndarray], size: int) -> Iterator[np.ndarray]:
    """Consecutive runs of ``size`` rows (the last may be shorter) across ``pieces`` in order:
    a piece's end joins the next piece's start, so the runs do not depend on the cutting."""
    carry: np.ndarray | None = None
    for piece in pieces:
        start = 0
        if carry is not None:
            start = min(size - len(carry), len(piece))
            carry = np.concatenate([carry, piece[:start]])
            if len(carry) < size:
                continue
            yield carry
            carry = None
        stop = start + (len(piece) - start) // size * size
        for first in range(start, stop, size):
            yield piece[first:first + size]
        if stop < len(piece):
            carry = piece[stop:]
    if carry is not None and len(carry):
        yield carry


def array_source(fmt: str, triangles: np.ndarray, dtype: str, warnings: tuple[CodedWarning, ...] = ()) -> MeshSource:
    """A ``MeshSource`` over an in-memory ``(n, 3, 3)`` triangle array."""

    def read_blocks() -> Iterator[np.ndarray]:
        for start in range(0, len(triangles), BLOCK):
            yield triangles[start:start + BLOCK]

    return MeshSource(fmt, int(len(triangles)), dtype, read_blocks, None, tuple(warnings))
