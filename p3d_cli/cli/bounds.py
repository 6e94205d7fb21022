"""``p3d bounds``: the exact axis-aligned box of meshes and shapes, after placement."""

from __future__ import annotations

import functools

import click

from p3d_cli import measure, shapes
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import (
    PLACEMENT_HELP,
    batch_options,
    field_option,
    format_option,
    inputs_argument,
    json_option,
    placement_options,
    precision_option,
    units_options,
    warning_options,
)
from p3d_cli.cli.output import plural
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.cli.settings import WarningFilter, settings_for
from p3d_cli.results import bounds_record


def _and(names: list[str]) -> str:
    """``a, b and c``."""
    return ", ".join(names[:-1]) + " and " + names[-1] if len(names) > 1 else "".join(names)


@click.command(help=f"""Exact axis-aligned bounds of meshes and shapes, after --scale, a rotation
and --translate.

Exact for every class: meshes, {_and(shapes.names(polyhedral=True))} by projecting their vertices;
{_and(shapes.names(polyhedral=False))} by closed forms. {PLACEMENT_HELP} Rotations are active, about
the world origin, right-hand rule: --rotate z:90 takes the x axis to the y axis; several
--rotate turns are each applied after the previous one about the fixed world axes.

\b
Inputs: mesh files, - for standard input, or shape specs, a name alone being unit scale (the
canonical [-1,1]³ shape) and scale factors half-extents (box:1,2,3 measures 2 x 4 x 6):
{shapes.spec_lines()}

A sphere keeps sx=sy=sz and a cylinder sx=sy; ellipsoid and ecylinder are their exact
generalisations. A file named like a spec is reached as ./box. Directories are searched for mesh files, and
--files-from, --jobs, --dask and --csv work as for p3d props (see docs/batch.md).

\b
Examples:
  p3d bounds part.stl --rotate z:30 --rotate x:90
  p3d bounds cylinder:1,1,2 --rotate 1,1,0:45 --translate 0,0,5 --json
  p3d bounds box:1,2,3 --quat 0.9239,0,0,0.3827
  p3d bounds exports/ --csv --jobs 4 > boxes.csv
  p3d bounds part.stl --units mm --output-units m
  p3d bounds assembly.yaml --json
""")
@inputs_argument
@format_option
@placement_options
@json_option
@field_option
@precision_option
@warning_options
@batch_options
@units_options
def bounds(inputs, fmt, placement, tessellate, units, output_units, as_json, fields, precision, settings, batch):
    style = output.output_style(as_json, batch.csv, fields, "table")
    run = Batch("p3d bounds", inputs, batch)
    if style in ("table", "fields"):
        run.note_settings(settings.config, "bounds", {"units": units})
    if batch.csv:
        click.echo(output.csv_header("bounds"))
    run.report(functools.partial(bounds_report, style=style, placement=placement, tessellate=tessellate,
                                 format=fmt, units=units, output_units=output_units, fields=fields,
                                 precision=precision, settings=settings),
               functools.partial(error_line, style=style))
    return run.finish("failed")


def bounds_report(source: str, *, style: str, fields: tuple[str, ...] = (), precision: int | None = None,
                  settings: WarningFilter = WarningFilter(), **options) -> Report:
    """One input's bounds in ``style`` (table, json, csv or fields), formatted where they were
    computed (module level, so that worker processes can receive it)."""
    used = settings_for(settings.config, "bounds", source, options)
    result = measure.bounds(source, **options)
    kept = settings.keep(result.source, result.warnings)
    if style == "table":
        return Report(bounds_table(result, precision or 10), source=result.source, warnings=kept)
    record = bounds_record(result)
    record["settings"] = used
    return Report(output.formatted("bounds", record, style, fields, precision), source=result.source, warnings=kept)


def error_line(outcome, *, style: str) -> str | None:
    """The record of an input that could not be done: JSON or CSV, an empty line for --field;
    nothing in table style."""
    return output.failed("bounds", outcome.source, error_message(outcome.error), style)


def bounds_table(result, precision: int = 10) -> str:
    b = result.bounds
    faces = "" if result.format == "primitive" else f", {plural(result.faces, 'face')}"
    vector = functools.partial(output.vector, precision=precision, width=max(17, precision + 7))
    return "\n".join([
        f"{output.shown_name(result.source)}  ({result.format}{faces}, {result.method})",
        f"  min      {vector(b.min)}",
        f"  max      {vector(b.max)}",
        f"  size     {vector(b.size)}",
        f"  center   {vector(b.center)}",
    ])
