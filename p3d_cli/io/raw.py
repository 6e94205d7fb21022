"""The bytes of one input: a file on disk (read lazily, in pieces) or standard input."""

from __future__ import annotations

import errno
import io
import os
import stat
import sys
import time
from dataclasses import dataclass

from p3d_cli.errors import InputError, ReadError


@dataclass(frozen=True)
class RawInput:
    """One input's bytes.

    Attributes
    ----------
    where : str
        Its name in messages: the path as given, or ``<stdin>``.
    path : str or None
        The path as given (for its extension); None for standard input.
    data : bytes or None
        The whole content, for standard input and pipes (then read instead of ``path``).
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


#: Most bytes read from a pipe or FIFO (and standard input): a stream has no size to check
#: before reading, so this bounds the memory an endless writer can take.
STREAM_LIMIT = 1 << 32
#: Seconds a FIFO is waited for a writer before it counts as empty.
FIFO_WAIT = 10.0


def open_input(source: str, stdin=None) -> RawInput:
    """Check that ``source`` can be read and describe it (nothing big is read yet).

    A pipe or FIFO (``<(gunzip -c part.stl.gz)``) is read whole, like standard input; a FIFO
    with no writer reads as empty instead of blocking. Devices (``/dev/zero``) are refused.

    Raises
    ------
    InputError
        Missing file, a broken or looping symbolic link, a directory, a device, permission
        denied, an empty input, or a stream longer than ``STREAM_LIMIT``.
    """
    if source == "-":
        stream = stdin if stdin is not None else sys.stdin.buffer
        data = _read_stream(stream, "<stdin>")
        if not data:
            raise InputError("<stdin>", "standard input is empty", "pipe a mesh into p3d, e.g. p3d props - < part.stl")
        return RawInput("<stdin>", None, data, len(data))
    mode = _mode(source)
    if stat.S_ISDIR(mode):
        raise ReadError(source, "is a directory", "name the mesh files, or pass the directory to a batch command")
    if stat.S_ISFIFO(mode) or stat.S_ISSOCK(mode):
        return _open_pipe(source)
    if not stat.S_ISREG(mode):
        raise ReadError(source, "is a device, not a file", "name a mesh file, or pipe the mesh into p3d with -")
    try:
        size = os.path.getsize(source)
        with open(source, "rb"):
            pass
    except PermissionError:
        raise ReadError(source, "permission denied", "check the file's permissions") from None
    except OSError as exc:
        raise ReadError(source, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    if size == 0:
        raise InputError(source, "file is empty", "export the mesh again")
    return RawInput(source, source, None, size)


def _mode(source: str) -> int:
    """``st_mode`` of ``source``, with errors that say what is wrong with the path."""
    if source == "":
        raise ReadError("''", "an empty path names no file", "give the mesh's path or a shape spec")
    try:
        return os.stat(source).st_mode
    except FileNotFoundError:
        if os.path.islink(source):
            raise ReadError(source, f"a broken symbolic link (to {os.readlink(source)!r})",
                             "point the link at the mesh, or name the mesh itself") from None
        from p3d_cli.shapes import SHAPES

        raise ReadError(source, "no such file",
                        f"check the path (shape specs are {', '.join(SHAPES)})") from None
    except PermissionError:
        raise ReadError(source, "permission denied", "check the permissions of the file and its folders") from None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise ReadError(source, "a loop of symbolic links", "point the link at the mesh itself") from None
        raise ReadError(source, f"cannot be read ({exc.strerror or exc})", "check the path") from None


def _open_pipe(source: str) -> RawInput:
    """Read a FIFO or socket whole, waiting up to ``FIFO_WAIT`` seconds for a writer.

    A blocking ``open`` of a FIFO waits for a writer forever; so it is opened non-blocking, and
    until a writer shows up (a read then gives data or "would block" instead of end-of-file),
    polled. Then reads block as usual, and the writer's end-of-file ends the input.
    """
    try:
        fd = os.open(source, os.O_RDONLY | os.O_NONBLOCK)
    except PermissionError:
        raise ReadError(source, "permission denied", "check the file's permissions") from None
    except OSError as exc:
        raise ReadError(source, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    with os.fdopen(fd, "rb", buffering=0) as stream:
        first = _first_bytes(stream, time.monotonic() + FIFO_WAIT)
        os.set_blocking(fd, True)
        data = first + _read_stream(stream, source) if first is not None else b""
    if not data:
        raise InputError(source, f"the pipe delivered no data (nothing wrote to it within {FIFO_WAIT:g} s)",
                         "start the program that writes the mesh first, or pipe it into p3d with -")
    return RawInput(source, source, data, len(data))


def _first_bytes(stream, deadline: float) -> bytes | None:
    """The first bytes a writer sends (b"" once a writer is there), or None if none came."""
    while True:
        try:
            piece = stream.read(1 << 20)
        except BlockingIOError:
            return b""          # a writer holds the other end: wait for it with blocking reads
        if piece is None:
            return b""
        if piece:
            return piece
        if time.monotonic() >= deadline:
            return None
        time.sleep(0.02)


def _read_stream(stream, where: str) -> bytes:
    pieces: list[bytes] = []
    total = 0
    while True:
        piece = stream.read(1 << 20)
        if not piece:
            return b"".join(pieces)
        total += len(piece)
        if total > STREAM_LIMIT:
            raise InputError(where, f"the stream holds more than {STREAM_LIMIT} bytes",
                             "save the mesh to a file and name the file")
        pieces.append(piece)
