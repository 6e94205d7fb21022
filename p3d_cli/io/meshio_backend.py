"""meshio backend (temporary: being written)."""

from p3d_cli.errors import UnknownFormatError


def knows_extension(ext: str) -> bool:
    return False


def knows_format(name: str) -> bool:
    return False


def format_for_extension(ext: str) -> str:
    raise KeyError(ext)


def load(raw, name=None):
    raise UnknownFormatError(raw.where, "meshio formats are not available yet", "use STL")
