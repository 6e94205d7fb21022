"""Reading a scene file's YAML safely, refusing duplicate mapping keys.

PyYAML's ``safe_load`` never constructs Python objects, but it silently keeps the last of
two equal keys, so a body named twice would lose its first definition without a word. The
loader below is a ``SafeLoader`` subclass whose mapping constructor refuses that.
"""

from __future__ import annotations

import yaml

from p3d_cli.errors import SceneError


class DuplicateKeyError(yaml.constructor.ConstructorError):
    """Raised inside the loader; turned into a ``SceneError`` by ``read_yaml``."""

    def __init__(self, path: str, key, line: int) -> None:
        super().__init__(None, None, f"duplicate key {key!r}")
        self.path = path
        self.key = key
        self.line = line


class UniqueKeySafeLoader(yaml.SafeLoader):
    """A ``SafeLoader`` that refuses a mapping holding the same key twice."""


def _construct_unique_mapping(loader: UniqueKeySafeLoader, node: yaml.MappingNode, deep: bool = False):
    loader.flatten_mapping(node)
    seen: dict = {}
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=True)
        try:
            hash(key)
        except TypeError:
            raise yaml.constructor.ConstructorError(
                None, None, "a mapping key must be a plain value", key_node.start_mark) from None
        if key in seen:
            raise DuplicateKeyError("", key, key_node.start_mark.line + 1)
        seen[key] = key_node
    return loader.construct_mapping(node, deep=deep)


UniqueKeySafeLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG,
                                    _construct_unique_mapping)


def read_yaml(path: str, where: str):
    """The plain data (dicts, lists, scalars) of a YAML file.

    Parameters
    ----------
    path : str
        The file to read.
    where : str
        Its name in messages.

    Raises
    ------
    SceneError
        The file cannot be read, is not valid YAML, or repeats a key in one mapping.
    """
    try:
        with open(path, "rb") as f:
            text = f.read()
    except OSError as exc:
        raise SceneError(where, f"cannot read the scene file ({exc.strerror or exc})",
                         "check the path and its permissions") from None
    try:
        return yaml.load(text, Loader=UniqueKeySafeLoader)  # noqa: S506 - a SafeLoader subclass
    except DuplicateKeyError as exc:
        raise SceneError(f"{where}:{exc.line}", f"key {exc.key!r} appears twice in one mapping",
                         "YAML would silently keep only the last one; rename or remove one") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        place = f"{where}:{mark.line + 1}" if mark is not None else where
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise SceneError(place, f"not valid YAML: {problem}",
                         "fix the syntax (indentation, colons, brackets)") from None
