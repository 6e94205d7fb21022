"""``p3d props``: volume, mass, centre of mass and inertia of meshes and shapes."""

from __future__ import annotations

import functools

import click

from p3d_cli.cli import output
from p3d_cli.cli.batch import Batch
from p3d_cli.cli.options import VECTOR3, batch_options, density_options, format_option, inputs_argument, json_option, strict_option
from p3d_cli.cli.options import placement_options
from p3d_cli.errors import CheckFailedError, UsageError
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
    failed = warned = False
    if method != "montecarlo" and (samples is not None or seed is not None or tolerance is not None):
        raise UsageError("--samples/--seed/--tolerance", "given without --method montecarlo",
                         "add --method montecarlo, or drop them")

    if batch.csv and (as_json or fields):
        raise UsageError("--csv", "given with --json or --field", "choose one output format")
    run = Batch("p3d props", inputs, batch)
    compute = functools.partial(compute_props, method=method, samples=samples, seed=seed,
                                tolerance=tolerance, fmt=fmt, density=density, mass=mass, about=about,
                                placement=placement, tessellate=tessellate)
    if batch.csv:
        click.echo(output.csv_line(output.PROPS_CSV_COLUMNS))
    for outcome in run.outcomes(compute):
        if outcome.error is not None:
            failed = True
            run.error(outcome)
            if as_json or batch.csv:
                record = {"source": outcome.source, "error": outcome.error.message}
                click.echo(output.csv_line(output.props_row(record)) if batch.csv else output.dumps(record))
            continue
        result = outcome.result
        for text in result.warnings:
            run.note(f"p3d: warning: {result.facts.source}: {text}")
        warned = warned or bool(result.warnings)
        run.fail() if strict and result.warnings else run.passed()
        record = output.props_record(result)
        if batch.csv:
            click.echo(output.csv_line(output.props_row(record)))
        elif fields:
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
    status = run.finish("with warnings (--strict)")
    if failed:
        raise click.exceptions.Exit(status)
    if strict and warned:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")


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
