"""``p3d bounds``: the exact axis-aligned box of meshes and shapes, after placement."""

from __future__ import annotations

import functools

import click

from p3d_cli.cli import output
from p3d_cli.cli.batch import Batch, BatchOptions, Report
from p3d_cli.cli.options import PLACEMENT_HELP, format_option, inputs_argument, json_option, placement_options
from p3d_cli.placed import input_bounds


@click.command(help=f"""Exact axis-aligned bounds of meshes and shapes, after --scale, a rotation
and --translate.

Exact for every class: meshes, box, wedge and corner by projecting their vertices; sphere,
cylinder, ellipsoid and ecylinder by closed forms. {PLACEMENT_HELP} Rotations are active, about
the world origin, right-hand rule: --rotate z:90 takes the x axis to the y axis; several
--rotate turns are each applied after the previous one about the fixed world axes.

\b
Inputs: mesh files, - for standard input, or shape specs:
  box, wedge, corner, cylinder, sphere     unit scale (the canonical [-1,1]³ shape)
  box:SX,SY,SZ                             half-extents: box:1,2,3 measures 2 x 4 x 6
  sphere:R   cylinder:R,R,H                a sphere keeps sx=sy=sz, a cylinder sx=sy
  ellipsoid:A,B,C   ecylinder:A,B,H        their exact generalisations
A file named like a spec is reached as ./box.

\b
Examples:
  p3d bounds part.stl --rotate z:30 --rotate x:90
  p3d bounds cylinder:1,1,2 --rotate 1,1,0:45 --translate 0,0,5 --json
  p3d bounds box:1,2,3 --quat 0.9239,0,0,0.3827
""")
@inputs_argument
@format_option
@placement_options
@json_option
def bounds(inputs, fmt, placement, tessellate, as_json):
    run = Batch("p3d bounds", inputs, BatchOptions(jobs=1))
    run.report(functools.partial(bounds_report, as_json=as_json, placement=placement, tessellate=tessellate,
                                 fmt=fmt),
               lambda outcome: output.dumps({"source": outcome.source, "error": outcome.error.message})
               if as_json else None)
    status = run.finish()
    if status:
        raise click.exceptions.Exit(status)


def bounds_report(source: str, *, as_json: bool, **options) -> Report:
    """One input's bounds, formatted."""
    result = input_bounds(source, **options)
    notes = tuple(f"p3d: warning: {result.source}: {text}" for text in result.warnings)
    return Report(output.dumps(bounds_record(result)) if as_json else bounds_table(result), notes)


def bounds_record(result) -> dict:
    """The JSON object of ``p3d bounds`` for one input (stable keys)."""
    b = result.bounds
    return {
        "source": result.source,
        "format": result.format,
        "method": result.method,
        "faces": result.faces,
        "min": b.min,
        "max": b.max,
        "size": b.size,
        "center": b.center,
        "diagonal": b.diagonal,
        "warnings": list(result.warnings),
    }


def bounds_table(result) -> str:
    b = result.bounds
    faces = "" if result.format == "primitive" else f", {result.faces} faces"
    return "\n".join([
        f"{result.source}  ({result.format}{faces}, {result.method})",
        f"  min      {output.vector(b.min)}",
        f"  max      {output.vector(b.max)}",
        f"  size     {output.vector(b.size)}",
        f"  center   {output.vector(b.center)}",
    ])
