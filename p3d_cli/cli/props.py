"""``p3d props``: volume, mass, centre of mass and inertia of meshes and shapes."""

from __future__ import annotations

import functools

import click

from p3d_cli import measure
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import (
    VECTOR3,
    batch_options,
    density_options,
    field_option,
    format_option,
    inputs_argument,
    json_option,
    placement_options,
    precision_option,
    strict_option,
    units_options,
    warning_options,
)
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.cli.rounding import snapped
from p3d_cli.cli.settings import WarningFilter, settings_for
from p3d_cli.errors import CheckFailedError, UsageError
from p3d_cli.results import INERTIA_CONVENTION, PropsResult, props_record


@click.command()
@inputs_argument
@format_option
@density_options
@click.option("--about", type=VECTOR3, default=None, metavar="X,Y,Z",
              help="Also report the inertia about this point.")
@json_option
@field_option
@precision_option
@strict_option
@warning_options
@click.option("--method", type=click.Choice(["exact", "montecarlo"]), default="exact", show_default=True,
              help="exact: divergence theorem / closed form, with rounding-error bounds. montecarlo: "
                   "sample the bounding box with an inside test, with standard errors (an "
                   "independent check of a mesh you distrust).")
@click.option("--samples", type=click.IntRange(min=2), default=None, metavar="N",
              help="Monte Carlo sample count (default 100000, at most 100000000).")
@click.option("--seed", type=click.IntRange(min=0), default=None, metavar="S",
              help="Monte Carlo random seed (default 0): the same seed gives the same numbers.")
@click.option("--tolerance", type=click.FloatRange(min=0, min_open=True), default=None, metavar="REL",
              help="Monte Carlo: pick the sample count for this relative standard error of the volume.")
@placement_options
@batch_options
@units_options
@click.option("--combine", is_flag=True,
              help="Measure the inputs as one assembly (one placement and density for all; "
                   "--mass is the whole's): each part and the whole, as for an assembly file.")
@click.option("--emit", type=click.Choice(["urdf", "mjcf", "sdf"]), default=None,
              help="Print a ready <inertial> block for a robot description (SI with --units; "
                   "the frame convention in a comment; docs/robots.md).")
@click.option("--intersections", is_flag=True,
              help="Also test a mesh exactly for self-intersections and for closed shells nested wound "
                   "alike, as p3d check does (warnings self-intersecting, nested-shells).")
@click.option("--shells", is_flag=True,
              help="Measure each closed shell of a mesh (with the cavities inside it) as a part of an "
                   "assembly: the bodies of a multi-body export, and the whole (implies --intersections).")
def props(inputs, fmt, density, mass, about, as_json, fields, precision, strict, settings, method, samples, seed,
          tolerance, batch, placement, tessellate, units, output_units, combine, emit=None, intersections=False,
          shells=False):
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
      p3d props part.stl --units mm --density 7.85g/cm^3
      p3d props assembly.yaml --json
      p3d props a.stl b.stl --combine --units mm --density 2.7g/cm^3
      p3d props export.stl --shells --json

    Shape specs (box:1,2,3, sphere:0.5; p3d bounds --help lists them all) give exact closed
    forms. --scale, --rotate/--quat and --translate place the solid
    (scale first, then rotation about the world origin, then translation); the centre of mass
    and inertia reported are the placed solid's (I' = R I Rᵀ).

    Units (docs/units.md): --units names the mesh's length unit; densities and masses may
    carry units (7.85g/cm^3, 7850kg/m^3, 0.284lb/in^3, 2.5kg, 2.5lb, 500g); results are then
    in SI (or --output-units) and every output says its units. An assembly file (YAML with
    parts:, docs/assemblies.md) is measured part by part and as a whole.

    A surface that intersects itself, or closed shells nested wound alike, count some volume
    twice: --intersections tests for that exactly (it also runs when the inertia is not a
    solid's), --shells measures each body of a multi-body export on its own (docs/ci.md).
    """
    style = output.output_style(as_json, batch.csv, fields, "table")
    style = f"emit:{emit}" if emit else style
    options = dict(placement=placement, method=method, density=density, mass=mass, about=about,
                   tessellate=tessellate, samples=samples, seed=seed, tolerance=tolerance, format=fmt,
                   units=units, output_units=output_units)
    if shells and combine:
        raise UsageError("--shells/--combine", "both given", "--shells splits one mesh into its bodies; "
                         "--combine joins several inputs: choose one")
    if intersections or shells:     # only when asked: the props of every other caller stay as they were
        options.update(intersections=intersections, shells=shells)
    measure.check_props_options(method, density, mass, tessellate, samples, seed, tolerance)
    run = Batch("p3d props", inputs, batch)
    if style in ("table", "fields") or style.startswith("emit:"):
        run.note_settings(settings.config, "props", options)
    work = functools.partial(props_report, style=style, fields=fields, strict=strict, settings=settings,
                             precision=precision, **options)
    if batch.csv:
        click.echo(output.csv_header("props", about=about is not None))
    if combine:
        return combined(run, work)
    run.report(work, functools.partial(error_line, style=style, about=about is not None))
    status = run.finish("with warnings (--strict)")
    if run.failed and not run.errors:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")
    return status


def combined(run: Batch, work) -> int:
    """``--combine``: the inputs as one assembly, one report (an unreadable input ends it)."""
    from p3d_cli.measure import combine

    bad = [item for item in run.items if not isinstance(item, str)]
    if bad:
        raise bad[0]
    assembly = combine(run.items, "combined")
    given = work.keywords.get("density") is not None or work.keywords.get("mass") is not None
    config = work.keywords["settings"].config
    if not given and config.paths:
        # Each part's own [[paths]] density (the top level's stays the default of the rest).
        import dataclasses

        parts = []
        for part in assembly.parts:
            options = {"units": work.keywords.get("units"), "density": None, "mass": None}
            settings_for(config, "props", part.thing, options)
            own = options["density"] if options["density"] != config.settings.get("density") else None
            parts.append(dataclasses.replace(part, density=own))
        assembly = dataclasses.replace(assembly, parts=tuple(parts))
    report = work(assembly)
    run.record(report, "combined")      # its notes and warnings to stderr, its verdict for the reports
    click.echo(report.text)
    run.write_reports()
    if not report.passed:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")
    return 0


def props_report(src, *, style: str, fields: tuple[str, ...], strict: bool, settings: WarningFilter = WarningFilter(),
                 precision: int | None = None, **options) -> Report:
    """One input's output in ``style`` (table, json, csv or fields), formatted where it was
    computed (module level, so that worker processes can receive it).

    Raises
    ------
    FieldError
        A name in ``fields`` that the result does not have.
    """
    used = settings_for(settings.config, "props", src, options)
    result = measure.props(src, **options)
    kept = settings.keep(result.facts.source, result.warnings)
    if style == "table":
        text = props_table(result, precision or 10)
    elif style.startswith("emit:"):
        from p3d_cli.robots.emit import emit_result

        text = emit_result(style[5:], result)
    else:
        record = props_record(result)
        record["settings"] = used
        text = output.formatted("props", record, style, fields, precision, about=options.get("about") is not None)
    failed = strict and bool(kept)
    return Report(text, passed=not failed, source=result.facts.source, warnings=kept,
                  failures=kept if failed else ())


def error_line(outcome, *, style: str, about: bool = False) -> str | None:
    """The record of an input that could not be done: JSON or CSV, an empty line for --field
    (so that lines stay aligned with inputs); nothing in the table."""
    return output.failed("props", outcome.source, error_message(outcome.error), style, about=about)


def units_line(units: dict | None) -> list[str]:
    """The table's statement of units, 80 columns wide."""
    if not units or units.get("system") == "mesh":
        return ["  units             the mesh's own (no units given)"]
    return [f"  units             length {units['length']}, mass {units['mass']}, inertia {units['inertia']} "
            f"(mesh in {units['mesh_length']})"]


def props_table(result: PropsResult, precision: int = 10) -> str:
    """A readable block for one input, 80 columns wide (a long file name aside); values within
    their rounding bound of zero as 0. For an assembly: each part's block, then the whole."""
    blocks = [props_table(part, precision) for part in result.parts]
    f = result.facts
    p = snapped(props_record(result))
    closed = {True: "yes", False: "NO", None: "n/a"}[f.closed]
    number = functools.partial(output.number, precision=precision)
    vector = functools.partial(output.vector, precision=precision, width=max(17, precision + 7))
    name = f"part {result.details['name']}: " if "name" in result.details else ""
    whole = "whole " if result.parts else ""
    objects = f"{result.details['objects']}, " if "objects" in result.details else ""
    lines = [
        whole + name + output.shown_name(f.source),
        f"  {f.format}, " + ("" if f.format == "primitive" else f"{output.plural(f.faces, 'face')}, ")
        + f"{objects}closed: {closed}, method: {result.method}",
        *units_line(result.units),
        f"  volume            {number(p['volume'])}",
        f"  density           {number(p['density'])}",
        f"  mass              {number(p['mass'])}",
        f"  center of mass    {vector(p['center_of_mass'])}",
    ]
    if p["inertia"] is None:
        lines.append("  inertia           - (no volume)")
    else:
        lines.append("  inertia about the centre of mass")
        lines.append("    (" + INERTIA_CONVENTION + ")")
        lines += [f"                    {vector(row)}" for row in p["inertia"]]
        lines.append("  inertia about the origin")
        lines += [f"                    {vector(row)}" for row in p["inertia_origin"]]
        if p.get("inertia_about") is not None:
            lines.append(f"  inertia about ({', '.join(number(x) for x in p['about'])})")
            lines += [f"                    {vector(row)}" for row in p["inertia_about"]]
        lines.append(f"  principal moments {vector(p['principal_moments'])}")
        lines.append("  principal axes (rows; right-handed)")
        lines += [f"                    {vector(row)}" for row in p["principal_axes"]]
    if f.bounds is not None:
        lines.append(f"  bounds min        {vector(f.bounds.min)}")
        lines.append(f"  bounds max        {vector(f.bounds.max)}")
    return "\n".join(blocks + lines)
