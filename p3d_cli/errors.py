"""The exception hierarchy of p3d: one root, each class carrying its exit code.

The library raises these; ``p3d_cli.cli.main`` is the one place that turns them into a
message of the form ``p3d: error: <where>: <what>; <how to fix>`` and an exit status.

Exit statuses (documented in the README and ``p3d --help``):

- 0: success.
- 1: the inputs were read but a result failed a requirement (``p3d check`` found a
  defect, ``--strict`` met a warning).
- 2: usage error or input that cannot be used (missing, unreadable or corrupt file,
  bad option value, invalid scene).
- 3: internal error (a bug in p3d; please report it).

Each class also derives from the builtin a caller would catch (as rasterio's
``RasterioIOError(RasterioError, OSError)``): a value or file contents that make no sense are a
``ValueError`` (``InputError``, ``UsageError`` and theirs), a file that cannot be read or
written an ``OSError`` (``ReadError``, ``OutputError``), a missing optional package an
``ImportError`` (``MissingExtraError``). So ``except ValueError`` around ``p3d.props(...)``
catches a bad spec, and ``except OSError`` a missing file.
"""

from __future__ import annotations


class P3DError(Exception):
    """Root of every error p3d raises on purpose.

    Parameters
    ----------
    where : str
        The place the problem is: a file path, ``scene.yaml: bodies.arm.mass``, an option.
    what : str
        What is wrong, in words.
    hint : str, optional
        How to fix it.
    """

    exit_code = 2
    #: In a batch, an error met on one input normally becomes that input's error record;
    #: True ends the whole batch instead (see ``p3d_cli.cli.batch.Batch.report``).
    ends_batch = False

    def __init__(self, where: str, what: str, hint: str = "") -> None:
        self.where = where
        self.what = what
        self.hint = hint
        super().__init__(self.message)

    def __reduce__(self):
        # Rebuilt from (where, what, hint) rather than from ``args`` (the joined message), so
        # that an error crosses into and out of worker processes and Dask as itself.
        return _rebuild, (type(self), self.where, self.what, self.hint, self.__dict__.copy())

    @property
    def message(self) -> str:
        text = f"{self.where}: {self.what}" if self.where else self.what
        return f"{text}; {self.hint}" if self.hint else text


def _rebuild(cls, where: str, what: str, hint: str, state: dict) -> P3DError:
    # A class that is an OSError and, through InputError, a ValueError is built by OSError's
    # ``__new__`` (the one its layout needs); ``cls.__new__`` would find ValueError's first.
    error = OSError.__new__(cls) if issubclass(cls, OSError) else cls.__new__(cls)
    P3DError.__init__(error, where, what, hint)
    error.__dict__.update(state)
    return error


class InputError(P3DError, ValueError):
    """An input (file, stream, spec) cannot be read or makes no sense."""


class ReadError(InputError, OSError):
    """A file or stream cannot be read at all: missing, a directory, permission denied, a broken
    link (an ``OSError``, and still an ``InputError``, as ``io.UnsupportedOperation`` is both)."""


class FormatError(InputError):
    """A file's bytes do not follow its format (truncated, corrupt, lying header)."""


class RangeError(InputError):
    """A number the input leads to is outside float64's range: it would overflow to infinity or
    underflow to zero (a part of size 1e200 has a volume of 1e600)."""


class UnknownFormatError(InputError):
    """p3d cannot tell, or does not read, the file's format."""


class UsageError(P3DError, ValueError):
    """An option or argument value is invalid."""


class FieldError(UsageError):
    """A ``--field`` that a result does not have: found only once a result exists, but wrong for
    the whole command line, so it ends the batch."""

    ends_batch = True


class SpecError(UsageError):
    """A primitive shape spec (``box:1,2,3``) is malformed or breaks a scale rule."""


class SceneError(InputError):
    """A constraint scene file is invalid."""


class OutputError(P3DError, OSError):
    """A file p3d was asked to write cannot be written, or writing it would damage a file (an
    input, a read-only file): nothing is written then (``p3d_cli.io.atomic``)."""


class MissingExtraError(P3DError, ImportError):
    """An optional backend is needed but not installed."""


def install_hint(extra: str, requirements: str) -> str:
    """How to install p3d's extra ``extra`` (whose packages are ``requirements``, as pip takes
    them): p3d itself is not on PyPI, so the hint names the packages, and the extra of a clone."""
    return f"install p3d's extra '{extra}': pip install {requirements} (or pip install '.[{extra}]' in a clone of p3d)"


class CheckFailedError(P3DError):
    """A result failed a requirement (``--strict``, ``p3d check``)."""

    exit_code = 1


class InternalError(P3DError):
    """A bug met while working on one input of a batch: reported in that input's place."""

    exit_code = 3
