"""``p3d props``: volume, mass, centre of mass and inertia of meshes and shapes."""

from __future__ import annotations

import functools

import click
import numpy as np

from p3d_cli import measure
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import (
    VECTOR3,
    batch_options,
    density_options,
    format_option,
    inputs_argument,
    json_option,
    placement_options,
    strict_option,
    units_options,
)
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.errors import CheckFailedError, FieldError, UsageError
from p3d_cli.results import PropsResult


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
@units_options
@click.option("--combine", is_flag=True,
              help="Measure the inputs as one assembly (one placement and density for all; "
                   "--mass is the whole's): each part and the whole, as for an assembly file.")
@batch_options
def props(inputs, fmt, density, mass, about, as_json, fields, strict, method, samples, seed, tolerance, batch,
          placement, tessellate, units, output_units, combine):
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

    Shape specs (box, wedge, corner, cylinder, sphere, ellipsoid, ecylinder; see p3d bounds
    --help) give exact closed forms. --scale, --rotate/--quat and --translate place the solid
    (scale first, then rotation about the world origin, then translation); the centre of mass
    and inertia reported are the placed solid's (I' = R I Rᵀ).

    Units (docs/units.md): --units names the mesh's length unit; densities and masses may
    carry units (7.85g/cm^3, 7850kg/m^3, 0.284lb/in^3, 2.5kg, 2.5lb, 500g); results are then
    in SI (or --output-units) and every output says its units. An assembly file (YAML with
    parts:, docs/assemblies.md) is measured part by part and as a whole.
    """
    if batch.csv and (as_json or fields):
        raise UsageError("--csv", "given with --json or --field", "choose one output format")
    style = "csv" if batch.csv else "fields" if fields else "json" if as_json else "table"
    options = dict(placement=placement, method=method, density=density, mass=mass, about=about,
                   tessellate=tessellate, samples=samples, seed=seed, tolerance=tolerance, format=fmt,
                   units=units, output_units=output_units)
    measure.check_props_options(method, density, mass, tessellate, samples, seed, tolerance)
    run = Batch("p3d props", inputs, batch)
    work = functools.partial(props_report, style=style, fields=fields, strict=strict, **options)
    if batch.csv:
        click.echo(output.csv_line(CSV_COLUMNS))
    if combine:
        return combined(run, work)
    run.report(work, functools.partial(error_line, style=style))
    status = run.finish("with warnings (--strict)")
    if run.failed and not run.errors:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")
    return status


def combined(run: Batch, work) -> int:
    """``--combine``: the inputs as one assembly, one report (an unreadable input ends it)."""
    from p3d_cli.assembly import combine

    bad = [item for item in run.items if not isinstance(item, str)]
    if bad:
        raise bad[0]
    report = work(combine(run.items, "combined"))
    for line in report.notes:
        click.echo(line, err=True)
    click.echo(report.text)
    if not report.passed:
        raise CheckFailedError("--strict", "some result carries a warning (see above)",
                               "fix the mesh, or drop --strict to accept it")
    return 0


def props_report(src, *, style: str, fields: tuple[str, ...], strict: bool, **options) -> Report:
    """One input's output in ``style`` (table, json, csv or fields), formatted where it was
    computed (module level, so that worker processes can receive it).

    Raises
    ------
    FieldError
        A name in ``fields`` that the result does not have.
    """
    result = measure.props(src, **options)
    notes = tuple(f"p3d: warning: {result.facts.source}: {text}" for text in result.warnings)
    if style == "table":
        text = props_table(result)
    else:
        record = props_record(result)
        if style == "csv":
            rows = [{**part, "source": f"{record['source']}#{part['name']}"} for part in record.get("parts", ())]
            text = "\n".join(output.csv_line(props_row(row)) for row in rows + [record])
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
    record = {"source": outcome.source, "error": error_message(outcome.error)}
    if style == "csv":
        return output.csv_line(props_row(record))
    return output.dumps(record) if style == "json" else None


INERTIA_CONVENTION = "positive tensor: Ixx = ∫(y²+z²) dm, Ixy = -∫xy dm"


def props_record(result: PropsResult) -> dict:
    """The JSON object of ``p3d props`` for one input (stable keys)."""
    p, f = result.properties, result.facts
    record = {
        "source": f.source,
        "format": f.format,
        "method": result.method,
        "faces": f.faces,
        "closed": f.closed,
        "volume": p.volume,
        "mass": p.mass,
        "density": p.density,
        "center_of_mass": p.center_of_mass,
        "inertia": p.inertia,
        "inertia_origin": p.inertia_origin,
        "principal_moments": p.principal_moments,
        "principal_axes": p.principal_axes,
        "principal_quaternion": p.principal_quaternion,
        "principal_rpy": p.principal_rpy,
        "second_moments": p.second_moments,
        "bounds": None if f.bounds is None else {"min": f.bounds.min, "max": f.bounds.max},
        "coordinate_dtype": f.coordinate_dtype,
        "inertia_convention": INERTIA_CONVENTION,
        "warnings": list(result.warnings),
        "uncertainty": result.uncertainty,
    }
    if p.about is not None:
        record["about"] = p.about
        record["inertia_about"] = p.inertia_about
    record.update(result.details)
    record["units"] = result.units
    if result.parts:
        record["parts"] = [props_record(part) for part in result.parts]
    return record


def units_line(units: dict | None) -> str:
    """The table's statement of units."""
    if not units or units.get("system") == "mesh":
        return "  units             the mesh's own (no units given)"
    return (f"  units             length {units['length']}, mass {units['mass']}, inertia {units['inertia']} "
            f"(mesh in {units['mesh_length']})")


def props_table(result: PropsResult) -> str:
    """A readable block for one input (for an assembly: each part's block, then the whole)."""
    blocks = [props_table(part) for part in result.parts]
    p, f = result.properties, result.facts
    closed = {True: "yes", False: "NO", None: "n/a"}[f.closed]
    name = f"part {result.details['name']}: " if "name" in result.details else ""
    whole = "whole " if result.parts else ""
    objects = f"{result.details['objects']}, " if "objects" in result.details else ""
    lines = [
        f"{whole}{name}{f.source}  ({f.format}, {objects}{f.faces} faces, closed: {closed}, method: {result.method})",
        units_line(result.units),
        f"  volume            {output.number(p.volume)}",
        f"  density           {output.number(p.density)}",
        f"  mass              {output.number(p.mass)}",
        f"  center of mass    {output.vector(p.center_of_mass)}",
    ]
    if p.inertia is None:
        lines.append("  inertia           - (no volume)")
    else:
        lines.append("  inertia about the centre of mass (" + INERTIA_CONVENTION + ")")
        lines += [f"                    {output.vector(row)}" for row in p.inertia]
        lines.append("  inertia about the origin")
        lines += [f"                    {output.vector(row)}" for row in p.inertia_origin]
        if p.inertia_about is not None:
            lines.append(f"  inertia about ({', '.join(output.number(x) for x in p.about)})")
            lines += [f"                    {output.vector(row)}" for row in p.inertia_about]
        lines.append(f"  principal moments {output.vector(p.principal_moments)}")
        lines.append("  principal axes (rows; right-handed)")
        lines += [f"                    {output.vector(row)}" for row in p.principal_axes]
    if f.bounds is not None:
        lines.append(f"  bounds min        {output.vector(f.bounds.min)}")
        lines.append(f"  bounds max        {output.vector(f.bounds.max)}")
    return "\n".join(blocks + lines)


#: Columns of ``p3d props --csv``: inertia about the centre of mass, positive tensor convention.
CSV_COLUMNS = ("source", "format", "method", "faces", "closed", "volume", "mass", "density",
                     "com_x", "com_y", "com_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz",
                     "warnings", "error")


def props_row(record: dict) -> list:
    """The ``--csv`` cells of a ``props_record`` (or of an error record), in column order."""
    row = dict.fromkeys(CSV_COLUMNS)
    row.update({k: v for k, v in record.items() if k in row})
    com, inertia = record.get("center_of_mass"), record.get("inertia")
    if com is not None:
        row["com_x"], row["com_y"], row["com_z"] = (float(x) for x in com)
    if inertia is not None:
        i = np.asarray(inertia)
        row.update(ixx=i[0, 0], iyy=i[1, 1], izz=i[2, 2], ixy=i[0, 1], ixz=i[0, 2], iyz=i[1, 2])
    row["warnings"] = " | ".join(record.get("warnings") or []) or None
    return [row[k] for k in CSV_COLUMNS]
