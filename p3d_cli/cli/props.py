"""``p3d props``: volume, mass, centre of mass and inertia of meshes and shapes."""

from __future__ import annotations

import functools

import click

from p3d_cli.cli import output
from p3d_cli.cli.batch import Batch, Report
from p3d_cli.cli.options import VECTOR3, batch_options, density_options, format_option, inputs_argument, json_option, strict_option
from p3d_cli.cli.options import placement_options
from p3d_cli.errors import CheckFailedError, FieldError, UsageError
from p3d_cli.placed import input_props


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
@placement_options
@batch_options
def props(inputs, fmt, density, mass, about, as_json, fields, strict, method, samples, seed, tolerance, batch,
          placement, tessellate):
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
      p3d props box:1,2,3 --rotate z:30 --translate 0,0,5 --density 7850
      p3d props sphere:2 --tessellate 64

    Shape specs (box, wedge, corner, cylinder, sphere, ellipsoid, ecylinder; see p3d bounds
    --help) give exact closed forms. --scale, --rotate/--quat and --translate place the solid
    (scale first, then rotation about the world origin, then translation); the centre of mass
    and inertia reported are the placed solid's (I' = R I Rᵀ).
    """
    if density is not None and mass is not None:
        raise UsageError("--mass/--density", "both given", "give one: the other follows from the volume")
    if method != "montecarlo" and (samples is not None or seed is not None or tolerance is not None):
        raise UsageError("--samples/--seed/--tolerance", "given without --method montecarlo",
                         "add --method montecarlo, or drop them")

    if batch.csv and (as_json or fields):
        raise UsageError("--csv", "given with --json or --field", "choose one output format")
    style = "csv" if batch.csv else "fields" if fields else "json" if as_json else "table"
    run = Batch("p3d props", inputs, batch)
    work = functools.partial(props_report, style=style, fields=fields, strict=strict, method=method,
                             samples=samples, seed=seed, tolerance=tolerance, fmt=fmt, density=density,
                             mass=mass, about=about, placement=placement, tessellate=tessellate)
    if batch.csv:
        click.echo(output.csv_line(output.PROPS_CSV_COLUMNS))
    run.report(work, functools.partial(error_line, style=style))
    status = run.finish("with warnings (--strict)")
    if run.errors:
        raise click.exceptions.Exit(status)
    if run.failed:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")


def props_report(src, *, style: str, fields: tuple[str, ...], strict: bool, **compute) -> Report:
    """One input's output in ``style`` (table, json, csv or fields), formatted where it was
    computed (module level, so that worker processes can receive it).

    Raises
    ------
    FieldError
        A name in ``fields`` that the result does not have.
    """
    result = compute_props(src, **compute)
    notes = tuple(f"p3d: warning: {result.facts.source}: {text}" for text in result.warnings)
    if style == "table":
        text = output.props_table(result)
    else:
        record = output.props_record(result)
        if style == "csv":
            text = output.csv_line(output.props_row(record))
        elif style == "fields":
            text = "\t".join(output.bare(field(record, name)) for name in fields)
        else:
            text = output.dumps(record)
    return Report(text, notes, passed=not (strict and result.warnings))


def field(record: dict, name: str):
    """``record``'s field ``name`` (dots for nesting)."""
    try:
        return output.field_value(record, name)
    except KeyError:
        raise FieldError("--field", f"no field named {name!r}", "fields are: " + ", ".join(record)) from None


def error_line(outcome, *, style: str) -> str | None:
    """The record of an input that could not be done: JSON or CSV; nothing in the other styles."""
    record = {"source": outcome.source, "error": outcome.error.message}
    if style == "csv":
        return output.csv_line(output.props_row(record))
    return output.dumps(record) if style == "json" else None


def compute_props(src, *, method, samples, seed, tolerance, fmt, density, mass, about,
                  placement=None, tessellate=None):
    """One input's ``PropsResult`` (module level, so that worker processes can receive it)."""
    if method == "montecarlo":
        if tessellate is not None:
            raise UsageError("--tessellate", "given with --method montecarlo",
                             "Monte Carlo samples the exact shape; drop one of them")
        from p3d_cli.montecarlo import montecarlo_props
        return montecarlo_props(src, samples=samples, seed=seed, tolerance=tolerance, fmt=fmt,
                                density=density, mass=mass, about=about, placement=placement)
    return input_props(src, placement, tessellate=tessellate, fmt=fmt, density=density, mass=mass,
                       about=about)
