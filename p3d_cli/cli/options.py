"""Options shared by several commands, defined once."""

from __future__ import annotations

import math

import click


class Vector3(click.ParamType):
    """``X,Y,Z``: three finite numbers separated by commas (a leading minus is fine)."""

    name = "X,Y,Z"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        parts = str(value).split(",")
        try:
            numbers = tuple(float(p) for p in parts)
        except ValueError:
            numbers = ()
        if len(numbers) != 3 or not all(math.isfinite(x) for x in numbers):
            self.fail(f"expected three finite numbers X,Y,Z, got {value!r}", param, ctx)
        return numbers


class FiniteFloat(click.ParamType):
    """A finite number, optionally required to be positive."""

    name = "NUMBER"

    def __init__(self, positive: bool = False) -> None:
        self.positive = positive

    def convert(self, value, param, ctx):
        try:
            x = float(value)
        except (TypeError, ValueError):
            self.fail(f"expected a number, got {value!r}", param, ctx)
        if not math.isfinite(x):
            self.fail(f"expected a finite number, got {value!r}", param, ctx)
        if self.positive and x <= 0:
            self.fail(f"must be positive, got {value!r}", param, ctx)
        return x


class Scale(click.ParamType):
    """``S`` (uniform) or ``SX,SY,SZ``: finite non-zero numbers (negative ones mirror)."""

    name = "S|SX,SY,SZ"

    def convert(self, value, param, ctx):
        if isinstance(value, tuple):
            return value
        try:
            numbers = tuple(float(p) for p in str(value).split(","))
        except ValueError:
            numbers = ()
        if len(numbers) not in (1, 3) or not all(math.isfinite(x) and x != 0 for x in numbers):
            self.fail(f"expected S or SX,SY,SZ, each finite and positive (or negative to mirror), "
                      f"got {value!r}", param, ctx)
        return numbers * 3 if len(numbers) == 1 else numbers


class Quantity(click.ParamType):
    """A positive number, bare or with a unit (``7850``, ``7.85g/cm^3``, ``2.5lb``).

    A bare number becomes a float; text with a unit is handed to the library as it is, which
    parses it (``p3d_cli.units``) only then, so the unit library is loaded only when used.
    """

    name = "NUMBER[UNIT]"

    def convert(self, value, param, ctx):
        if isinstance(value, float):
            return value
        try:
            x = float(value)
        except (TypeError, ValueError):
            return str(value)
        if not math.isfinite(x) or x <= 0:
            self.fail(f"must be a positive finite number, got {value!r}", param, ctx)
        return x


VECTOR3 = Vector3()


def inputs_argument(f):
    # click.Path: shells complete file names for the inputs (no check here: specs are inputs too).
    return click.argument("inputs", nargs=-1, metavar="INPUT...", type=click.Path())(f)


def format_option(f):
    return click.option("--format", "fmt", metavar="NAME",
                        help="Read every input as this format (stl, obj, ply, off, gltf/glb, 3mf, "
                             "dae/collada, amf, vtp, or a meshio format name) instead of guessing "
                             "from content and extension.")(f)


def json_option(f):
    return click.option("--json", "as_json", is_flag=True,
                        help="One JSON object per input, one per line (full float64 precision).")(f)


def density_options(f):
    f = click.option("--mass", type=Quantity(), default=None,
                     help="Total mass, bare or with a unit (2.5kg, 2.5lb, 500g); the density is "
                          "derived from the volume.")(f)
    f = click.option("--density", type=Quantity(), default=None,
                     help="Mass per unit volume (default 1), bare (in the mesh's units) or with a "
                          "unit: 7.85g/cm^3, 7850kg/m^3, 0.284lb/in^3.")(f)
    return f


def units_options(f):
    """``--units`` (the mesh's length unit) and ``--output-units``, handed on as ``units`` and
    ``output_units``."""
    from p3d_cli.units import LENGTHS

    names = "|".join(LENGTHS)
    f = click.option("--output-units", "output_units", default=None, metavar="LENGTH,MASS",
                     help="Units of the results when units are given (default m,kg: SI), e.g. "
                          "mm,g or in,lb.")(f)
    f = click.option("--units", type=click.Choice(list(LENGTHS)), default=None, metavar=names,
                     help=f"Length unit of the mesh and of the numbers given with it (--about, "
                          f"--translate): {', '.join(LENGTHS)}. With units, results are in SI "
                          f"(kg, m, kg·m²) unless --output-units says otherwise; without, in "
                          f"the mesh's own units.")(f)
    return f


def strict_option(f):
    return click.option("--strict", is_flag=True,
                        help="Exit with status 1 when any result carries a warning "
                             "(open, inward-wound, flat or coarse mesh).")(f)


def batch_options(f):
    """``--files-from``, ``-0``, ``--jobs``, ``--dask``, ``--csv``, ``--report``, ``--summary``,
    handed to the command as one ``batch: BatchOptions`` argument (see ``p3d_cli.cli.reporting``)."""
    import functools

    from p3d_cli.cli.reporting import BatchOptions
    from p3d_cli.cli.reports import parse_reports

    @functools.wraps(f)
    def command(*args, files_from, null, jobs, dask, as_csv, reports, summary, quiet, **kwargs):
        jobs, dask = _environment_defaults(jobs, dask)
        return f(*args, batch=BatchOptions(files_from, jobs, dask, as_csv, null, parse_reports(reports, summary),
                                           quiet), **kwargs)

    command = click.option("--quiet", "-q", is_flag=True,
                           help="No progress bar, summary, settings line or warnings on stderr: only "
                                "errors (and the results on stdout).")(command)
    command = report_options(command)
    command = click.option("--csv", "as_csv", is_flag=True,
                           help="A CSV table: a header, then one row per input (error rows fill "
                                "the error column).")(command)
    command = click.option("--dask", metavar="ADDRESS", default=None, envvar="P3D_DASK", show_envvar=True,
                           help="Run the batch on an existing Dask cluster (e.g. "
                                "tcp://scheduler:8786; needs p3d's extra 'dask', and p3d and the same "
                                "paths on the workers). Default: $P3D_DASK, if set; --jobs on the "
                                "command line wins over it.")(command)
    command = click.option("--jobs", "-j", type=click.IntRange(min=1), default=None, metavar="N",
                           envvar="P3D_JOBS", show_envvar=True,
                           help="Worker processes on this machine (default: $P3D_JOBS, else one per "
                                "core; one input or -j 1 runs in this process).")(command)
    command = click.option("--null", "-0", "null", is_flag=True,
                           help="The --files-from list is NUL-separated (git ls-files -z, find "
                                "-print0): names are kept exactly, spaces and newlines too.")(command)
    command = click.option("--files-from", metavar="LIST", default=None, type=click.Path(),
                           help="Also read input paths from LIST, one per line (- for standard "
                                "input).")(command)
    return command


def _environment_defaults(jobs, dask):
    """``--jobs`` and ``--dask`` after their environment defaults (``P3D_JOBS``, ``P3D_DASK``):
    an option given on the command line wins over the other's environment default, so that
    ``P3D_DASK`` set in a shell does not make ``-j 4`` a usage error (nor ``P3D_JOBS``
    ``--dask``). An empty ``P3D_DASK`` is no address."""
    from click.core import ParameterSource

    context = click.get_current_context(silent=True)
    if dask == "":
        dask = None
    if context is None or jobs is None or dask is None:
        return jobs, dask
    source = context.get_parameter_source
    if source("dask") == ParameterSource.ENVIRONMENT and source("jobs") != ParameterSource.ENVIRONMENT:
        return jobs, None
    if source("jobs") == ParameterSource.ENVIRONMENT and source("dask") != ParameterSource.ENVIRONMENT:
        return None, dask
    return jobs, dask


#: How --scale, --rotate/--quat and --translate combine; quoted in the commands' help.
PLACEMENT_HELP = ("Placement order: --scale (in the solid's own frame), then the rotation "
                  "(--rotate, --quat or --rpy) about the world origin, then --translate.")


def placement_options(f):
    """``--scale``, ``--rotate``, ``--quat``, ``--translate``, ``--tessellate``, handed to the
    command as ``placement: p3d_cli.geometry.placement.Placement`` and ``tessellate: int | None``."""
    import functools

    from p3d_cli import shapes

    @functools.wraps(f)
    def command(*args, scale, turns, quat, rpy, translate, tessellate, **kwargs):
        return f(*args, placement=make_placement(scale, turns, quat, translate, rpy),
                 tessellate=tessellate, **kwargs)

    command = click.option("--tessellate", type=click.IntRange(min=3), default=None, metavar="N",
                           help=f"Replace a round shape spec ({', '.join(shapes.names(polyhedral=False))}) "
                                "by an inscribed polyhedron of N segments, to see how far the "
                                "polyhedral approximation is from the exact shape.")(command)
    command = click.option("--translate", type=VECTOR3, default=None, metavar="X,Y,Z",
                           help="Move the solid by X,Y,Z (applied last).")(command)
    command = click.option("--quat", default=None, metavar="W,X,Y,Z",
                           help="Rotate by the quaternion W + Xi + Yj + Zk (scalar first), "
                                "normalised for you; q and -q give the same rotation; a leading "
                                "minus is fine (--quat -0.7,0.1,0.7,0). Not with --rotate or --rpy.")(command)
    command = click.option("--rpy", default=None, metavar="R,P,Y",
                           help="Rotate by roll-pitch-yaw angles in radians, URDF's convention: "
                                "about the fixed axes, first R about x, then P about y, then Y "
                                "about z (R = Rz Ry Rx). Not with --rotate or --quat.")(command)
    command = click.option("--rotate", "turns", multiple=True, metavar="AXIS:DEGREES",
                           help="Turn by DEGREES about AXIS (x, y, z or a vector such as 1,1,0) "
                                "through the world origin, right-hand rule. Repeatable: each turn "
                                "is applied after the previous one about the fixed world axes "
                                "(R = Rn...R2 R1).")(command)
    command = click.option("--scale", type=Scale(), default=None, metavar="S|SX,SY,SZ",
                           help="Scale the solid by S (uniform) or SX,SY,SZ along its own axes, "
                                "about the origin (applied first; mass properties by eq. 9 of the "
                                "Physics3D note, exact for any diagonal scale). A negative factor "
                                "mirrors the solid (its winding is flipped so the mirror has a "
                                "positive volume). A sphere or cylinder scaled unevenly becomes "
                                "the ellipsoid or elliptic cylinder. For unit conversion use "
                                "--units.")(command)
    return command


def make_placement(scale, turns, quat, translate, rpy=None):
    """The ``Placement`` of the placement options, or None when none was given.

    Raises
    ------
    UsageError
        A malformed turn, quaternion or rpy, a zero scale, or two ways of giving the rotation.
    """
    from p3d_cli.io.placements import make_placement as placement

    return placement(scale=scale, turns=turns or None, quat=quat, rpy=rpy, translate=translate,
                     names=("--rotate", "--quat", "--rpy"))


def report_options(f):
    """``--report`` (repeatable) and ``--summary``: reports CI systems read (``p3d_cli.cli.reports``);
    the command receives their raw values as ``reports`` and ``summary``."""
    f = click.option("--summary", metavar="json:FILE", default=None,
                     help="Write the counts (ok, warned, failed, errored, skipped, skipped by "
                          "extension, warnings by code) as one JSON object to FILE.")(f)
    f = click.option("--report", "reports", multiple=True, metavar="KIND[:FILE]",
                     help="Also write a report for CI: junit:FILE (JUnit XML, one testcase per "
                          "input), github (GitHub Actions annotations on stdout) or github:FILE, "
                          "html:DIR (a page with each input's picture) or github-summary:FILE (the same "
                          "as Markdown, appended to FILE). Repeatable.")(f)
    return f


def warning_options(f):
    """``--ignore-warning``, ``--warning-threshold`` and ``--no-config``, handed to the command as
    ``settings: p3d_cli.cli.settings.WarningFilter`` (with the project settings loaded)."""
    import functools

    from p3d_cli.warning_codes import CODES

    @functools.wraps(f)
    def command(*args, ignore_warning, warning_threshold, no_config, **kwargs):
        return f(*args, settings=make_warning_filter(ignore_warning, warning_threshold, no_config), **kwargs)

    command = click.option("--no-config", is_flag=True,
                           help="Ignore the project settings (p3d.toml, or [tool.p3d] in "
                                "pyproject.toml, found from the working directory up).")(command)
    command = click.option("--warning-threshold", multiple=True, metavar="CODE=VALUE",
                           help="Silence a warning whose measured value is at most VALUE "
                                "(coarse-float32: spacing / part size, default 1e-6).")(command)
    command = click.option("--ignore-warning", multiple=True, metavar="CODE",
                           type=click.Choice(list(CODES)), show_choices=False,
                           help="Do not show or count warnings with this code (repeatable): "
                                + ", ".join(CODES) + ". JSON keeps them.")(command)
    return command


def make_warning_filter(ignore, thresholds, no_config: bool):
    """The ``WarningFilter`` of the warning options (and the project settings, unless
    ``no_config``).

    Raises
    ------
    UsageError, FormatError
    """
    from p3d_cli.cli.settings import WarningFilter, parse_thresholds
    from p3d_cli.cli.settings_file import Config, load_config

    config = Config() if no_config else load_config()
    limits = parse_thresholds((f"{k}={v}" for k, v in config.settings.get("warning-thresholds", {}).items()),
                              where=config.where("warning-thresholds"))
    limits.update(parse_thresholds(thresholds))
    return WarningFilter(frozenset(ignore), limits, config)


def field_option(f):
    """``--field NAME`` (repeatable), as ``fields: tuple[str, ...]``."""
    return click.option("--field", "fields", multiple=True, metavar="NAME",
                        help="Print only this JSON field, bare (repeatable; dots for nesting and "
                             "list indices: bounds.min, center_of_mass.0). Nested values print as "
                             "JSON; several fields go on one line, tab-separated; an input that "
                             "fails prints an empty line.")(f)


def precision_option(f):
    """``--precision N`` (significant digits of the table and of --csv), as ``precision``."""
    return click.option("--precision", type=click.IntRange(1, 17), default=None, metavar="N",
                        help="Significant digits of numbers in the table (default 10) and in "
                             "--csv (default 15); --json always keeps full precision.")(f)


def config_option(f):
    """``--no-config`` alone (for commands without warnings), handed on as ``config: Config``."""
    import functools

    @functools.wraps(f)
    def command(*args, no_config, **kwargs):
        from p3d_cli.cli.settings_file import Config, load_config

        return f(*args, config=Config() if no_config else load_config(), **kwargs)

    return click.option("--no-config", is_flag=True,
                        help="Ignore the project settings (p3d.toml, or [tool.p3d] in "
                             "pyproject.toml, found from the working directory up).")(command)
