"""OBJ reader (temporary: being written)."""

from p3d_cli.errors import UnknownFormatError


def looks_like_obj(head: bytes) -> bool:
    return False


def load(raw):
    raise UnknownFormatError(raw.where, "OBJ reading is not available yet", "use STL")
