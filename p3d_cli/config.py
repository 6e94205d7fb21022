"""A project's p3d settings: ``p3d.toml``, or ``[tool.p3d]`` in ``pyproject.toml``.

The file is found by walking up from the working directory; in each directory ``p3d.toml``
is looked for first, then a ``pyproject.toml`` that has a ``[tool.p3d]`` table. The first
found is the project's. Settings (kebab-case keys)::

    [tool.p3d]
    ignore-warnings = ["coarse-float32"]       # codes of p3d_cli.warning_codes
    warning-thresholds = { coarse-float32 = 1e-5 }
    density = 7850
    require = ["closed", "outward"]            # p3d check
    rtol = 1e-9                                # p3d diff; or a table per quantity:
    atol = { volume = 1e-12 }                  #   { volume = ..., mass = ..., ... }

    [[tool.p3d.paths]]                         # settings for the inputs matching a glob
    glob = "castings/*.stl"                    # relative to the file's directory; * crosses /
    density = 7100
    ignore-warnings = ["open"]

Precedence: the command line, then the last ``[[paths]]`` entry matching the input, then the
top-level settings, then p3d's defaults. ``units`` is accepted and kept for the units options.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from p3d_cli.errors import FormatError

#: Keys a settings table may hold, with the Python types of their values.
KEYS: dict[str, tuple[type, ...]] = {
    "ignore-warnings": (list,), "warning-thresholds": (dict,), "density": (int, float),
    "require": (list,), "rtol": (int, float, dict), "atol": (int, float, dict), "units": (str,),
}


@dataclass(frozen=True)
class Config:
    """The settings of one project file (empty when there is none).

    Attributes
    ----------
    path : str or None
        The file read.
    settings : dict
        The top-level settings.
    paths : tuple of (glob, dict)
        Settings for inputs matching a glob, in file order.
    """

    path: str | None = None
    settings: dict = field(default_factory=dict)
    paths: tuple[tuple[str, dict], ...] = ()

    def for_source(self, source: str) -> dict:
        """The settings for one input: the top level, updated by each matching ``paths`` entry."""
        merged = dict(self.settings)
        if not self.paths or self.path is None:
            return merged
        import fnmatch

        root = os.path.dirname(os.path.abspath(self.path))
        relative = os.path.relpath(os.path.abspath(source), root).replace(os.sep, "/")
        for pattern, settings in self.paths:
            if fnmatch.fnmatchcase(relative, pattern):
                merged.update(settings)
        return merged

    def get(self, key: str, source: str | None = None, default: Any = None) -> Any:
        """One setting, for ``source`` when given."""
        settings = self.settings if source is None else self.for_source(source)
        return settings.get(key, default)


def find_config(start: str | None = None) -> str | None:
    """The project file that governs ``start`` (default: the working directory), or None."""
    directory = os.path.abspath(start or os.getcwd())
    while True:
        candidate = os.path.join(directory, "p3d.toml")
        if os.path.isfile(candidate):
            return candidate
        pyproject = os.path.join(directory, "pyproject.toml")
        if os.path.isfile(pyproject) and _has_p3d_table(pyproject):
            return pyproject
        parent = os.path.dirname(directory)
        if parent == directory:
            return None
        directory = parent


def _has_p3d_table(pyproject: str) -> bool:
    """Whether a pyproject.toml has a ``[tool.p3d]`` table. The text is looked at first, so that
    most files are never parsed (start-up time) and a broken file of another project's that
    does not mention p3d cannot stop p3d."""
    try:
        with open(pyproject, encoding="utf-8", errors="replace") as f:
            text = f.read()
    except OSError:
        return False
    if "tool.p3d" not in text:
        return False
    return "p3d" in _read(pyproject).get("tool", {})


def load_config(path: str | None = None, start: str | None = None) -> Config:
    """The ``Config`` of ``path``, or of the project file found from ``start``; empty if none.

    Raises
    ------
    FormatError
        The file is not TOML, or a setting is unknown or of the wrong type.
    """
    path = path or find_config(start)
    if path is None:
        return Config()
    data = _read(path)
    table = data.get("tool", {}).get("p3d", {}) if os.path.basename(path) == "pyproject.toml" else data
    table = dict(table)
    entries = table.pop("paths", [])
    if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
        raise FormatError(path, "paths must be an array of tables ([[paths]] entries)",
                          'write [[tool.p3d.paths]] with glob = "..." and settings')
    paths = []
    for entry in entries:
        entry = dict(entry)
        pattern = entry.pop("glob", None)
        if not isinstance(pattern, str):
            raise FormatError(path, "a [[paths]] entry has no glob", 'add glob = "folder/*.stl"')
        paths.append((pattern, _checked(path, entry)))
    return Config(path, _checked(path, table), tuple(paths))


def _checked(path: str, settings: dict) -> dict:
    for key, value in settings.items():
        if key not in KEYS:
            raise FormatError(path, f"unknown p3d setting {key!r}", "settings are: " + ", ".join(KEYS))
        if not isinstance(value, KEYS[key]) or isinstance(value, bool):
            raise FormatError(path, f"setting {key!r} has a value of the wrong type ({type(value).__name__})",
                              "see the settings in docs/ci.md")
    if "ignore-warnings" in settings:
        from p3d_cli.warning_codes import check_codes

        check_codes(settings["ignore-warnings"], where=f"{path}: ignore-warnings")
    return settings


def _read(path: str) -> dict:
    try:
        import tomllib
    except ImportError:  # Python 3.10: the same parser, as a package
        try:
            import tomli as tomllib  # type: ignore[no-redef, unused-ignore]
        except ImportError:
            raise FormatError(path, "reading p3d settings needs Python 3.11 or the tomli package",
                              "pip install tomli, or pass --no-config") from None
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except tomllib.TOMLDecodeError as exc:
        raise FormatError(path, f"not valid TOML ({exc})", "fix the file, or pass --no-config") from None
    except OSError as exc:
        raise FormatError(path, f"cannot be read ({exc.strerror or exc})", "pass --no-config") from None


__all__ = ["Config", "KEYS", "find_config", "load_config"]
