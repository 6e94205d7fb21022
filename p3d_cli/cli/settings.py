"""What the command line resolves once per input: which warnings count, and the project
settings (``p3d_cli.cli.settings_file``) that apply to the input."""

from __future__ import annotations

from dataclasses import dataclass, field

from p3d_cli.cli.settings_file import Config
from p3d_cli.warning_codes import THRESHOLDS, check_codes, is_ignored


@dataclass(frozen=True)
class WarningFilter:
    """The warnings a command's user silenced, and the project settings (picklable: it
    travels to worker processes with the work).

    Attributes
    ----------
    ignore : frozenset of str
        Codes given with ``--ignore-warning``.
    thresholds : dict
        ``--warning-threshold CODE=VALUE``: a warning whose measured value is at most VALUE
        is silenced.
    config : Config
        The project settings (``ignore-warnings``, ``warning-thresholds`` per path glob).
    """

    ignore: frozenset = frozenset()
    thresholds: dict = field(default_factory=dict)
    config: Config = Config()

    def keep(self, source: str, warnings) -> tuple[tuple[str, str], ...]:
        """``(code, text)`` of each warning of ``source`` that is not silenced."""
        settings = self.config.for_source(source)
        ignore = self.ignore | frozenset(settings.get("ignore-warnings", ()))
        thresholds = {**settings.get("warning-thresholds", {}), **self.thresholds}
        return tuple((w.code, str(w)) for w in warnings if not is_ignored(w, ignore, thresholds))


def parse_thresholds(values, where: str = "--warning-threshold") -> dict[str, float]:
    """``CODE=VALUE`` pairs; only codes with a threshold, and not below the library's default
    (below it the library does not warn at all, so the setting could not be honoured).

    Raises
    ------
    UsageError
    """
    from p3d_cli.errors import UsageError

    out = {}
    for value in values:
        code, _, number = str(value).partition("=")
        try:
            limit = float(number)
        except ValueError:
            raise UsageError(where, f"{value!r} is not CODE=NUMBER", "e.g. coarse-float32=1e-5") from None
        check_codes([code], where)
        if code not in THRESHOLDS:
            raise UsageError(where, f"warning {code!r} has no threshold",
                             "thresholds: " + ", ".join(f"{k} (default {v:g})" for k, v in THRESHOLDS.items()))
        if not limit >= THRESHOLDS[code]:
            raise UsageError(where, f"{code} threshold {limit:g} is below p3d's {THRESHOLDS[code]:g}",
                             "a threshold can only be raised (p3d does not warn below its default)")
        out[code] = limit
    return out


def settings_for(config: Config, command: str, source, options: dict) -> dict | None:
    """Fill ``options`` (a measurement's keyword arguments) from the project settings for
    ``source`` where the command line gave nothing: ``units`` (the meshes' length unit) and
    ``density`` (unless ``--density`` or ``--mass`` was given). Returns what the output names
    (``Config.used``, with the keys the command line overrode left out), or None.

    An inconsistency between a setting and the units (a density with a unit but no length
    unit, or a bare density with one) is an error naming the file and the key, never a flag.

    Raises
    ------
    FormatError
    """
    from p3d_cli.errors import FormatError
    from p3d_cli.units import has_unit

    key = source if isinstance(source, str) else getattr(source, "where", None)   # a loaded mesh: its path
    used = config.used(command, key)
    if used is None:
        return None
    settings = config.for_source(key) if key is not None else config.settings
    keys = list(used["keys"])
    if "units" in options:
        if options.get("units") is None and "units" in settings:
            options["units"] = settings["units"]
        elif "units" in keys:
            keys.remove("units")
    if "density" in options:
        if options.get("density") is None and options.get("mass") is None and "density" in settings:
            density = options["density"] = settings["density"]
            where = config.where("density", key)
            if has_unit(density) and options.get("units") is None:
                raise FormatError(where, f"{density!r} has a unit, but no length unit is set for the meshes",
                                  'add units = "mm" (the unit of the meshes\' coordinates) to the file, '
                                  "or pass --units")
            if not has_unit(density) and options.get("units") is not None:
                raise FormatError(where, f"{density!r} has no unit, and the meshes' length unit is set "
                                  f"({options['units']})", 'write it with its unit: density = "7850 kg/m^3"')
        elif "density" in keys:
            keys.remove("density")
    return {"file": used["file"], "keys": keys} if keys else None


def settings_line(used: dict | None) -> str | None:
    """The stderr line naming a settings file that applies: ``p3d: settings: FILE (keys); ...``."""
    if not used:
        return None
    return (f"p3d: settings: {used['file']} applies ({', '.join(used['keys'])}); "
            "p3d config --show prints it, --no-config ignores it")
