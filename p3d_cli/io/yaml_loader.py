"""Reading a scene file's YAML safely, refusing duplicate mapping keys.

PyYAML's ``safe_load`` never constructs Python objects, but it silently keeps the last of
two equal keys, so a body named twice would lose its first definition without a word. The
loader below is a ``SafeLoader`` subclass whose mapping constructor refuses that.
"""

from __future__ import annotations

import os
import re

import yaml

from p3d_cli.errors import InputError, SceneError


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """Raised inside the loader; turned into a ``SceneError`` by ``read_yaml``."""

    def __init__(self, path: str, key, line: int) -> None:
        super().__init__(None, None, f"duplicate key {key!r}")
        self.path = path
        self.key = key
        self.line = line


class UniqueKeySafeLoader(yaml.SafeLoader):
    """A ``SafeLoader`` that refuses a mapping holding the same key twice."""


#: Largest scene file read (a scene of thousands of bodies is well under 1 MB): a device such as
#: /dev/zero, or a huge file given by mistake, is refused instead of filling memory.
MAX_SCENE_BYTES = 16 << 20

_MERGE = "tag:yaml.org,2002:merge"


def _construct_unique_mapping(loader: UniqueKeySafeLoader, node: yaml.MappingNode, deep: bool = False):
    # Keys written in this mapping must be unique; keys brought in by a merge (``<<: *defaults``)
    # may be overridden by a written key, as YAML's merge type says. So check before merging.
    seen: dict = {}
    for key_node, _ in node.value:
        if key_node.tag == _MERGE:
            continue
        key = loader.construct_object(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None, None, "a mapping key must be a plain value", key_node.start_mark) from None
        if key in seen:
            raise DuplicateKeyError("", key, key_node.start_mark.line + 1)
        seen[key] = key_node
    loader.flatten_mapping(node)  # merged keys first, so that written ones win
    return loader.construct_mapping(node, deep=deep)


UniqueKeySafeLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                                    _construct_unique_mapping)

# PyYAML follows YAML 1.1, whose floats need a dot: ``1e8`` and ``-2.5e-3`` without one would
# be read as the strings '1e8' and refused as "not a number", a trap for anyone who writes
# numbers as every programming language (and YAML 1.2) does. Such plain scalars are floats
# here too. (Added after the standard float resolver, so it only sees what that one missed.)
UniqueKeySafeLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float", re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"))


def _read_bounded(path: str) -> bytes:
    """At most ``MAX_SCENE_BYTES + 1`` bytes of ``path``. A FIFO is opened without blocking (no
    writer yet means nothing to read, not a wait forever)."""
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    with os.fdopen(fd, "rb") as f:
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)  # a writer that is there is read to its end
        return f.read(MAX_SCENE_BYTES + 1)


def read_yaml(path: str, where: str, error: type[InputError] = SceneError):
    """The plain data (dicts, lists, scalars) of a YAML file.

    Parameters
    ----------
    path : str
        The file to read.
    where : str
        Its name in messages.
    error : type
        The error raised (a scene's ``SceneError``; an assembly's or a mass list's ``InputError``).

    Raises
    ------
    SceneError (or ``error``)
        The file cannot be read, is not valid YAML, or repeats a key in one mapping.
    """
    try:
        text = _read_bounded(path)
    except OSError as exc:
        raise error(where, f"cannot be read ({exc.strerror or exc})",
                    "check the path and its permissions") from None
    if len(text) > MAX_SCENE_BYTES:
        raise error(where, f"is larger than {MAX_SCENE_BYTES >> 20} MB, far more than such a file needs",
                    "give the YAML file")
    try:
        return yaml.load(text, Loader=UniqueKeySafeLoader)  # noqa: S506 - a SafeLoader subclass
    except RecursionError:
        raise error(where, "nests lists or mappings too deeply to read",
                    "a scene needs a few levels of nesting; check the brackets") from None
    except (ValueError, OverflowError) as exc:
        # PyYAML's YAML 1.1 resolvers take some plain scalars for numbers or dates that its
        # constructors then cannot build (``0b_``, ``2001-13-45``) and let the Python error out.
        raise error(where, f"holds a value YAML takes for a number or a date but cannot read ({exc})",
                    "quote it if it is text, or write the number or date in full") from None
    except DuplicateKeyError as exc:
        raise error(f"{where}:{exc.line}", f"key {exc.key!r} appears twice in one mapping",
                    "YAML would silently keep only the last one; rename or remove one") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        place = f"{where}:{mark.line + 1}" if mark is not None else where
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise error(place, f"not valid YAML: {problem}",
                    "fix the syntax (indentation, colons, brackets)") from None
