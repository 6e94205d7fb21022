"""Files written whole or not at all: every file p3d writes goes through here.

A file p3d writes (a filled robot description, a report, a summary, a repaired mesh) is first
written to a temporary file in the destination's own folder, flushed to disk, given the
permissions of the file it replaces, and only then renamed over the destination
(``os.replace``, atomic on POSIX and Windows within one file system). A full disk, a kill or a
Ctrl-C part way leaves the destination as it was; the temporary file is removed on any error
the process lives through.

What would be damaged rather than replaced is refused before anything is written:

- a destination that is one of the command's inputs (``--report junit:part.stl`` naming the
  mesh being checked), unless the caller says the write is its documented in-place mode;
- a destination without write permission (renaming over a read-only file would succeed on
  POSIX, silently overriding the protection the user set);
- a destination with other hard links (a rename gives the path a new file, so the other names
  would keep the old content: the user expects all of them to change).

A symbolic link is followed: the file it points to is replaced and the link keeps working.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from pathlib import Path
from typing import BinaryIO, Iterable, Iterator

from p3d_cli.errors import OutputError, P3DError


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name one existing file (after links, ``..`` and case folding)."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def destination(path: str | os.PathLike, *, inputs: Iterable[str | os.PathLike] = (), in_place: bool = False,
                what: str = "output") -> Path:
    """The real file a write to ``path`` would replace, after the refusals above.

    Parameters
    ----------
    path : path
        Where the caller was asked to write.
    inputs : paths
        The files the command reads; writing over one is refused unless ``in_place``.
    in_place : bool
        The caller's documented mode for rewriting its input (``robot fill`` without
        ``--output``, ``repair --in-place``).
    what : str
        What is written, for messages (``"the JUnit report"``).

    Raises
    ------
    OutputError
    """
    target = Path(os.path.realpath(path))
    if not in_place:
        for source in inputs:
            if same_file(target, source):
                raise OutputError(str(path), f"{what} would overwrite the input {os.fspath(source)}",
                                  "write it to another path")
    try:
        info = os.stat(target)
    except FileNotFoundError:
        info = None
    except OSError as error:
        raise OutputError(str(path), f"cannot write {what}: {error.strerror}", "check the path") from None
    if info is not None:
        if not stat.S_ISREG(info.st_mode):
            raise OutputError(str(path), f"cannot write {what}: it exists and is not a regular file",
                              "name a file path")
        if not os.access(target, os.W_OK):
            raise OutputError(str(path), f"cannot write {what}: the file is read-only",
                              "make it writable (chmod u+w) or write elsewhere")
        if info.st_nlink > 1:
            raise OutputError(str(path), f"cannot replace {what}: the file has {info.st_nlink - 1} other hard "
                              "link(s), which would keep the old content", "write to another path")
    if not target.parent.is_dir():
        raise OutputError(str(path), f"cannot write {what}: the folder {target.parent} does not exist",
                          "create it first")
    return target


@contextlib.contextmanager
def replacing(path: str | os.PathLike, *, inputs: Iterable[str | os.PathLike] = (), in_place: bool = False,
              what: str = "output") -> Iterator[BinaryIO]:
    """A binary file to write ``path``'s new content into; it replaces ``path`` when the block
    ends without an exception, and is removed otherwise.

    Raises
    ------
    OutputError
        From ``destination``, or when the folder cannot take the file.
    """
    target = destination(path, inputs=inputs, in_place=in_place, what=what)
    try:
        handle, temporary = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".p3d-tmp")
    except OSError as error:
        raise OutputError(str(path), f"cannot write {what}: {error.strerror}",
                          "check the folder's permissions") from None
    done = False
    try:
        with os.fdopen(handle, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        _copy_permissions(target, temporary)
        os.replace(temporary, target)
        done = True
    except P3DError:
        raise  # the caller's own error, an OSError perhaps (ReadError): not a failure to write
    except OSError as error:
        raise OutputError(str(path), f"cannot write {what}: {error.strerror}",
                          "check the free space and the folder's permissions") from None
    finally:
        if not done:
            with contextlib.suppress(OSError):
                os.unlink(temporary)


def write_bytes(path: str | os.PathLike, data: bytes, *, inputs: Iterable[str | os.PathLike] = (),
                in_place: bool = False, what: str = "output") -> Path:
    """Write ``data`` to ``path`` through ``replacing``; returns the real path written."""
    with replacing(path, inputs=inputs, in_place=in_place, what=what) as f:
        f.write(data)
    return Path(os.path.realpath(path))


def _copy_permissions(target: Path, temporary: str) -> None:
    """Give the new file the old one's mode (and owner, where allowed); a new file gets the
    mode ``open`` would give it under the process's umask, not mkstemp's private 0600."""
    try:
        info = os.stat(target)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(temporary, 0o666 & ~umask)
        return
    os.chmod(temporary, stat.S_IMODE(info.st_mode))
    with contextlib.suppress(OSError):
        os.chown(temporary, info.st_uid, info.st_gid)
