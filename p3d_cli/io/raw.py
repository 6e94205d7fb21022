"""The bytes of one input: a file on disk (read lazily, in pieces) or standard input."""

from __future__ import annotations

import io
import os
import sys
from dataclasses import dataclass

from p3d_cli.errors import InputError


@dataclass(frozen=True)
class RawInput:
    """One input's bytes.

    Attributes
    ----------
    where : str
        Its name in messages: the path as given, or ``<stdin>``.
    path : str or None
        A readable file on disk; None for standard input.
    data : bytes or None
        The whole content, for standard input.
    size : int
        Length in bytes.
    """

    where: str
    path: str | None
    data: bytes | None
    size: int

    def open(self):
        """A binary stream positioned at the start."""
        if self.data is not None:
            return io.BytesIO(self.data)
        return open(self.path, "rb")

    def head(self, n: int) -> bytes:
        """The first ``n`` bytes (fewer if the input is shorter)."""
        if self.data is not None:
            return self.data[:n]
        with open(self.path, "rb") as f:
            return f.read(n)

    def read_all(self) -> bytes:
        """The whole content."""
        if self.data is not None:
            return self.data
        with open(self.path, "rb") as f:
            return f.read()


def open_input(source: str, stdin=None) -> RawInput:
    """Check that ``source`` can be read and describe it (nothing big is read yet).

    Raises
    ------
    InputError
        Missing file, a directory, permission denied, or an empty input.
    """
    if source == "-":
        stream = stdin if stdin is not None else sys.stdin.buffer
        data = stream.read()
        if not data:
            raise InputError("<stdin>", "standard input is empty", "pipe a mesh into p3d, e.g. p3d props - < part.stl")
        return RawInput("<stdin>", None, data, len(data))
    if not os.path.exists(source):
        raise InputError(source, "no such file", "check the path (primitive specs are box, wedge, corner, cylinder, sphere)")
    if os.path.isdir(source):
        raise InputError(source, "is a directory", "name the mesh files, or pass the directory to a batch command")
    try:
        size = os.path.getsize(source)
        with open(source, "rb"):
            pass
    except PermissionError:
        raise InputError(source, "permission denied", "check the file's permissions") from None
    except OSError as exc:
        raise InputError(source, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    if size == 0:
        raise InputError(source, "file is empty", "export the mesh again")
    return RawInput(source, source, None, size)
