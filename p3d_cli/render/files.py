"""Writing pictures to files, whole or not at all (``p3d_cli.io.atomic``)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

from p3d_cli.errors import UsageError

#: File formats a picture can be written in, by name and extension.
PICTURE_FORMATS = {".png": "png", ".svg": "svg"}


def picture_format(path: str | os.PathLike, format: str | None = None) -> str:
    """``png`` or ``svg``: ``format`` if given, else from the file's extension.

    Raises
    ------
    UsageError
        An unknown format, or an extension that names none.
    """
    if format is not None:
        if format not in PICTURE_FORMATS.values():
            raise UsageError("format", f"cannot write pictures as {format!r}", "use png or svg")
        return format
    ext = Path(os.fspath(path)).suffix.lower()
    if ext not in PICTURE_FORMATS:
        raise UsageError("output", f"{os.fspath(path)}: cannot tell the picture format from {ext or 'no extension'!r}",
                         "name a .png or .svg file")
    return PICTURE_FORMATS[ext]


def picture_bytes(picture, format: str) -> bytes:
    """The file content of ``picture`` in ``format`` (``png`` or ``svg``)."""
    return picture.to_png() if format == "png" else picture.to_svg().encode("utf-8")


def write_picture(picture, path: str | os.PathLike, *, format: str | None = None,
                  inputs: Iterable[str | os.PathLike] = ()) -> Path:
    """Write ``picture`` to ``path`` as PNG or SVG (by extension, or ``format``); the file is
    replaced only when complete, and never when it is one of ``inputs``.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    UsageError, OutputError
    """
    from p3d_cli.io.atomic import write_bytes

    kind = picture_format(path, format)
    return write_bytes(path, picture_bytes(picture, kind), inputs=inputs, what=f"the {kind.upper()} picture")
