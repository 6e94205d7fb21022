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
top-level settings, then p3d's defaults. ``units`` is the meshes' length unit (as ``--units``:
results are then in SI); with it, ``density`` carries its unit (``density = "7.85 g/cm^3"``).

A settings file that applies to an input is named in that input's output (``settings`` in
JSON; a line on stderr otherwise), so that a file in a parent folder never changes a result
unseen. Every error in the file names the file and the key (``p3d.toml: paths[1].density``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any

from p3d_cli.errors import FormatError

#: Keys a settings table may hold, with the Python types of their values.
KEYS: dict[str, tuple[type, ...]] = {
    "ignore-warnings": (list,), "warning-thresholds": (dict,), "density": (int, float, str),
    "require": (list,), "rtol": (int, float, dict), "atol": (int, float, dict), "units": (str,),
}

#: The settings each command's results depend on (what ``used`` reports for it).
AFFECTS: dict[str, tuple[str, ...]] = {
    "props": ("density", "units", "ignore-warnings", "warning-thresholds"),
    "bounds": ("units", "ignore-warnings", "warning-thresholds"),
    "check": ("require",),
    "diff": ("density", "units", "ignore-warnings", "warning-thresholds", "rtol", "atol"),
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

    def where(self, key: str, source: str | None = None) -> str:
        """``FILE: KEY`` or ``FILE: paths[i].KEY`` (the entry the value of ``key`` for ``source``
        comes from), for messages."""
        found = key
        if source is not None and self.paths and self.path is not None:
            root = os.path.dirname(os.path.abspath(self.path))
            relative = os.path.relpath(os.path.abspath(source), root).replace(os.sep, "/")
            import fnmatch

            for index, (pattern, settings) in enumerate(self.paths):
                if key in settings and fnmatch.fnmatchcase(relative, pattern):
                    found = f"paths[{index}].{key}"
        return f"{self.path}: {found}"

    def used(self, command: str, source: str | None = None) -> dict | None:
        """``{"file": PATH, "keys": [...]}``: the settings of this file that apply to ``source``
        in ``command`` (``AFFECTS``), or None when none do (or there is no file)."""
        if self.path is None:
            return None
        settings = self.settings if source is None else self.for_source(source)
        keys = [key for key in AFFECTS.get(command, ()) if key in settings]
        return {"file": self.path, "keys": keys} if keys else None


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
    paths: list[tuple[str, dict]] = []
    for entry in entries:
        entry = dict(entry)
        pattern = entry.pop("glob", None)
        if not isinstance(pattern, str):
            raise FormatError(path, "a [[paths]] entry has no glob", 'add glob = "folder/*.stl"')
        paths.append((pattern, _checked(path, entry, f"paths[{len(paths)}].")))
    return Config(path, _checked(path, table), tuple(paths))


def _checked(path: str, settings: dict, prefix: str = "") -> dict:
    """``settings`` after checking every key and value; errors name ``path`` and the key
    (``prefix`` + key: ``paths[0].density``)."""
    for key, value in settings.items():
        where = f"{path}: {prefix}{key}"
        if key not in KEYS:
            raise FormatError(f"{path}: {prefix}{key}", "unknown p3d setting", "settings are: " + ", ".join(KEYS))
        if not isinstance(value, KEYS[key]) or isinstance(value, bool):
            raise FormatError(where, f"a value of the wrong type ({type(value).__name__})",
                              "see the settings in docs/ci.md")
        _check_value(where, key, value)
    return settings


def _check_value(where: str, key: str, value: Any) -> None:
    """One setting's value, beyond its type (``FormatError`` naming ``where``)."""
    import math

    def number(x) -> bool:
        return isinstance(x, (int, float)) and not isinstance(x, bool)

    if key in ("ignore-warnings", "require"):
        bad = [x for x in value if not isinstance(x, str)]
        if bad:
            raise FormatError(where, f"{bad[0]!r} is not a name (text)", f'write {key} = ["name", ...]')
        if key == "ignore-warnings":
            from p3d_cli.errors import UsageError
            from p3d_cli.warning_codes import check_codes

            try:
                check_codes(value, where=where)
            except UsageError as exc:
                raise FormatError(exc.where, exc.what, exc.hint) from None
        else:
            from p3d_cli.mesh.verdicts import CHECKS

            names = [part.strip().lower() for x in value for part in x.split(",")]
            unknown = [n for n in names if n not in CHECKS and n not in ("all", "none")]
            if unknown:
                raise FormatError(where, f"no check named {unknown[0]!r}",
                                  "checks are: " + ", ".join(CHECKS) + " (or all, none)")
    elif key == "warning-thresholds" or (key in ("rtol", "atol") and isinstance(value, dict)):
        for name, x in value.items():
            if not number(x) or not x >= 0 or math.isinf(x):
                raise FormatError(f"{where}.{name}", f"{x!r} is not a non-negative number", "e.g. 1e-6")
    elif key in ("rtol", "atol", "density"):
        if number(value) and (not value >= 0 or math.isinf(value) or (key == "density" and value == 0)):
            raise FormatError(where, f"{value!r} is not a {'positive' if key == 'density' else 'non-negative'} "
                              "finite number", "e.g. 7850, or with units set, \"7.85 g/cm^3\"")
        if isinstance(value, str):   # a density with a unit: parsed now, so that its errors name the file
            from p3d_cli.errors import UsageError
            from p3d_cli.units import has_unit, quantity_si

            try:
                if not has_unit(value):
                    raise UsageError(where, f"{value!r} is text without a unit",
                                     "write a number (density = 7850) or a number and a unit (\"7.85 g/cm^3\")")
                quantity_si(value, "density", where)
            except UsageError as exc:
                raise FormatError(where, exc.what, exc.hint) from None
    elif key == "units":
        from p3d_cli.units import LENGTHS

        if value not in LENGTHS:
            raise FormatError(where, f"unknown length unit {value!r}", "use one of " + ", ".join(LENGTHS))


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


__all__ = ["AFFECTS", "Config", "KEYS", "find_config", "load_config"]
