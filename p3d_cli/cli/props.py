"""``p3d props``: volume, mass, centre of mass and inertia of meshes and shapes."""

from __future__ import annotations

import click

from p3d_cli.cli import output
from p3d_cli.cli.batch import run_each
from p3d_cli.cli.main_support import error_line
from p3d_cli.cli.options import VECTOR3, density_options, format_option, inputs_argument, json_option, strict_option
from p3d_cli.errors import CheckFailedError, UsageError
from p3d_cli.props import mesh_props


@click.command()
@inputs_argument
@format_option
@density_options
@click.option("--about", type=VECTOR3, default=None, metavar="X,Y,Z",
              help="Also report the inertia about this point.")
@json_option
@click.option("--field", "fields", multiple=True, metavar="NAME",
              help="Print only this JSON field, bare (repeatable; dots for nesting, e.g. "
                   "bounds.min). Several fields go on one line, tab-separated.")
@strict_option
@click.option("--method", type=click.Choice(["exact", "montecarlo"]), default="exact", show_default=True,
              help="exact: divergence theorem / closed form, with rounding-error bounds. montecarlo: "
                   "sample the bounding box with an inside test, with standard errors (an "
                   "independent check of a mesh you distrust).")
@click.option("--samples", type=click.IntRange(min=2), default=None, metavar="N",
              help="Monte Carlo sample count (default 100000).")
@click.option("--seed", type=click.IntRange(min=0), default=None, metavar="S",
              help="Monte Carlo random seed (default 0): the same seed gives the same numbers.")
@click.option("--tolerance", type=click.FloatRange(min=0, min_open=True), default=None, metavar="REL",
              help="Monte Carlo: pick the sample count for this relative standard error of the volume.")
def props(inputs, fmt, density, mass, about, as_json, fields, strict, method, samples, seed, tolerance):
    """Volume, mass, centre of mass and inertia of meshes and shapes.

    Integrals are exact (divergence theorem, float64, about a local origin so that a part's
    placement costs no accuracy). Inertia uses the positive tensor convention
    (Ixx = ∫(y²+z²) dm, Ixy = -∫xy dm), about the centre of mass unless stated. Meshes that
    are not clean solids (open, inward-wound, flat) still get results, with a warning on
    stderr and in the JSON.

    \b
    Examples:
      p3d props part.stl
      p3d props a.stl b.obj c.ply --json
      p3d props part.stl --density 7850 --about 0,0,0
      p3d props part.stl --field volume --field mass
      cat part.stl | p3d props - --format stl
      p3d props part.stl --method montecarlo --samples 1000000 --seed 7 --json
    """
    if not inputs:
        raise UsageError("p3d props", "no input given", "name a mesh file, a directory, or - for standard input")
    if density is not None and mass is not None:
        raise UsageError("--mass/--density", "both given", "give one: the other follows from the volume")
    failed = warned = False
    if method != "montecarlo" and (samples is not None or seed is not None or tolerance is not None):
        raise UsageError("--samples/--seed/--tolerance", "given without --method montecarlo",
                         "add --method montecarlo, or drop them")

    def compute(src):
        if method == "montecarlo":
            from p3d_cli.montecarlo import montecarlo_props
            return montecarlo_props(src, samples=samples, seed=seed, tolerance=tolerance, fmt=fmt,
                                    density=density, mass=mass, about=about)
        return mesh_props(src, fmt=fmt, density=density, mass=mass, about=about)

    for outcome in run_each(inputs, compute):
        if outcome.error is not None:
            failed = True
            error_line(outcome.error.message)
            if as_json:
                click.echo(output.dumps({"source": outcome.source, "error": outcome.error.message}))
            continue
        result = outcome.result
        for text in result.warnings:
            click.echo(f"p3d: warning: {result.facts.source}: {text}", err=True)
        warned = warned or bool(result.warnings)
        record = output.props_record(result)
        if fields:
            values = []
            for name in fields:
                try:
                    values.append(output.bare(output.field_value(record, name)))
                except KeyError:
                    raise UsageError("--field", f"no field named {name!r}",
                                     "fields are: " + ", ".join(record)) from None
            click.echo("\t".join(values))
        elif as_json:
            click.echo(output.dumps(record))
        else:
            click.echo(output.props_table(result))
    if failed:
        raise click.exceptions.Exit(2)
    if strict and warned:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")
