"""``p3d check``: is each mesh a clean, closed, outward-facing solid? One verdict per file."""

from __future__ import annotations

import functools

import click

from p3d_cli import measure
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import FiniteFloat, batch_options, format_option, inputs_argument, json_option
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.errors import UsageError
from p3d_cli.mesh.topology import CHECKS, CheckResult

#: Columns of ``--csv``, in order (the flat keys of the JSON record, then ``error``).
CSV_COLUMNS = ("source", "format", "ok", "failed", "faces", "vertices", "edges", "closed", "oriented",
               "outward", "manifold", "boundary_edges", "nonmanifold_edges", "misoriented_edges",
               "nonmanifold_vertices", "degenerate_faces", "zero_area_faces",
               "faces_with_repeated_vertex", "duplicate_faces", "shells", "volume", "error")

_COUNTS = (("boundary_edges", "boundary edge", "boundary_edge_samples"),
           ("nonmanifold_edges", "non-manifold edge", "nonmanifold_edge_samples"),
           ("misoriented_edges", "misoriented edge", "misoriented_edge_samples"),
           ("nonmanifold_vertices", "non-manifold vertex", "nonmanifold_vertex_samples"),
           ("degenerate_faces", "degenerate face", "degenerate_face_samples"),
           ("duplicate_faces", "duplicate face", "duplicate_face_samples"))


def check_report(source: str, *, style: str, **limits) -> Report:
    """One input's verdict in ``style`` (text, json or csv), formatted where it was computed
    (module level, so that worker processes can receive it)."""
    result = measure.check(source, **limits)
    if style == "text":
        text = check_text(result)
    else:
        record = check_record(result)
        text = output.dumps(record) if style == "json" else check_csv_line(record)
    return Report(text, passed=result.ok)


def error_line(outcome, *, style: str) -> str | None:
    """The record of an input that could not be read: JSON or CSV; nothing in text style."""
    record = {"source": outcome.source, "ok": False, "error": error_message(outcome.error)}
    if style == "text":
        return None
    return output.dumps(record) if style == "json" else check_csv_line(record)


def parse_require(values: tuple[str, ...]) -> tuple[str, ...]:
    """``--require`` values (repeatable, comma-separated; ``all``, ``none``) as check names."""
    if not values:
        return tuple(CHECKS)
    names: list[str] = []
    for value in values:
        for name in (part.strip().lower() for part in value.split(",")):
            if name == "all":
                names += list(CHECKS)
            elif name == "none":
                continue
            elif name in CHECKS:
                names.append(name)
            else:
                raise UsageError("--require", f"no check named {name!r}",
                                 "checks are: " + ", ".join(CHECKS) + " (or all, none)")
    return tuple(dict.fromkeys(names))


def check_record(result: CheckResult) -> dict:
    """The JSON object of ``p3d check`` for one input (stable keys)."""
    r = result.report
    record = {
        "source": result.source,
        "format": result.format,
        "ok": result.ok,
        "failed": list(result.failed),
        "required": list(result.required),
        "faces": r.faces,
        "vertices": r.vertices,
        "edges": r.edges,
        "closed": r.closed,
        "oriented": r.oriented,
        "outward": r.volume > 0,
        "manifold": r.manifold,
    }
    for key, _, _ in _COUNTS:
        record[key] = getattr(r, key)
    record.update({
        "zero_area_faces": r.zero_area_faces,
        "faces_with_repeated_vertex": r.faces_with_repeated_vertex,
        "shells": r.shells,
        "shell_list": [{"faces": s.faces, "first_face": s.first_face, "volume": s.volume}
                       for s in r.shell_list],
        "volume": r.volume,
        "samples": {key: [_sample_json(s) for s in getattr(r, samples)] for key, _, samples in _COUNTS},
        "vertex_matching": "exact coordinates (no tolerance; -0.0 equals 0.0)",
    })
    if result.parts:
        record["parts"] = [{"name": name, **check_record(part)} for name, part in result.parts]
    return record


def _sample_json(sample):
    if isinstance(sample, int):
        return sample
    if isinstance(sample, tuple):  # duplicate faces: (earlier face, later face)
        return list(sample)
    if hasattr(sample, "points"):
        return {"faces": list(sample.faces), "edge": [list(p) for p in sample.points]}
    return {"faces": list(sample.faces), "vertex": list(sample.point)}


def check_csv_line(record: dict) -> str:
    """The ``--csv`` row of a JSON record (or of an error record)."""
    row = {key: record.get(key, "") for key in CSV_COLUMNS}
    if isinstance(row["failed"], list):
        row["failed"] = " ".join(row["failed"])
    return output.csv_line(row[key] for key in CSV_COLUMNS)


def check_text(result: CheckResult) -> str:
    """A readable verdict for one input, with sample locations of each problem."""
    r = result.report
    shells = f"{r.shells} shell{'s' if r.shells != 1 else ''}"
    head = "ok" if result.ok else "FAILED " + ", ".join(result.failed)
    lines = [f"{result.source}: {head}  ({result.format}, {r.faces} faces, {shells}, "
             f"volume {output.number(r.volume)})"]
    for key, noun, samples in _COUNTS:
        count = getattr(r, key)
        if count:
            where = "; ".join(_sample_text(s) for s in getattr(r, samples))
            lines.append(f"  {count} {noun}{'s' if count != 1 else ''}{' (e.g. ' + where + ')' if where else ''}")
    if r.volume <= 0:
        lines.append("  signed volume is not positive: faces point inward (reverse the winding) or the "
                     "mesh encloses nothing")
    if r.shells > 1:
        listed = ", ".join(f"{output.number(s.volume)} ({s.faces} faces from face {s.first_face})"
                           for s in r.shell_list[:10])
        more = f", and {r.shells - 10} more" if r.shells > 10 else ""
        lines.append(f"  shell volumes: {listed}{more}")
    for name in ("min-volume", "max-faces"):
        if name in result.failed:
            lines.append(f"  over the {name} limit" if name == "max-faces" else "  below the min-volume limit")
    for _, part in result.parts:
        lines += ["  " + line for line in check_text(part).splitlines()]
    return "\n".join(lines)


def _sample_text(sample) -> str:
    if isinstance(sample, int):
        return f"face {sample}"
    if isinstance(sample, tuple):
        return f"face {sample[1]} repeats face {sample[0]}"
    faces = "face" + ("s " if len(sample.faces) != 1 else " ") + ",".join(map(str, sample.faces))
    if hasattr(sample, "points"):
        a, b = (", ".join(output.number(x) for x in p) for p in sample.points)
        return f"{faces} at ({a})-({b})"
    return f"{faces} at ({', '.join(output.number(x) for x in sample.point)})"


@click.command()
@inputs_argument
@format_option
@click.option("--require", "require", multiple=True, metavar="CHECK[,CHECK...]",
              help="Checks that must pass (repeatable or comma-separated): " + ", ".join(CHECKS)
                   + "; all (the default) or none.")
@click.option("--min-volume", type=FiniteFloat(), default=None, metavar="V",
              help="Also fail a mesh whose signed volume is below V.")
@click.option("--max-faces", type=click.IntRange(min=0), default=None, metavar="N",
              help="Also fail a mesh with more than N faces.")
@json_option
@batch_options
def check(inputs, fmt, require, min_volume, max_faces, as_json, batch):
    """Check that meshes are clean solids: one verdict per file, and an exit status.

    Each mesh is checked for being closed (every edge used by exactly two faces, in
    opposite directions), consistently oriented, outward-facing (positive signed volume),
    manifold (no edge used by more than two faces, no vertex joining separate fans), and
    free of degenerate (zero-area or repeated-vertex) and duplicate faces. Its connected
    shells are counted, each with its signed volume. Each problem comes with its count and a
    few locations (face indices from 0, edge end points). Vertices are matched by exact
    coordinates: nothing is merged within a tolerance. Every check is O(n log n).

    \b
    Exit statuses:
      0  every mesh passes the required checks and limits
      1  some mesh fails a check or a limit
      2  usage error, or some input cannot be read (the batch still goes on)
      3  a bug in p3d met on some input (please report it)

    Many inputs (files, directories, --files-from) give one result each, in input order,
    as they are ready; an input that cannot be read gives an error record and the batch
    goes on, and a summary goes to stderr.

    \b
    Examples:
      p3d check part.stl
      p3d check exports/ --json > verdicts.jsonl
      p3d check part.stl --require closed,outward --min-volume 1e-6 --max-faces 200000
      find . -name '*.stl' | p3d check --files-from - --csv --jobs 8
    """
    required = parse_require(require)
    if as_json and batch.csv:
        raise UsageError("--json/--csv", "both given", "choose one output format")
    style = "csv" if batch.csv else "json" if as_json else "text"
    run = Batch("p3d check", inputs, batch)
    work = functools.partial(check_report, style=style, format=fmt, require=required, min_volume=min_volume,
                             max_faces=max_faces)
    if batch.csv:
        click.echo(output.csv_line(CSV_COLUMNS))
    run.report(work, functools.partial(error_line, style=style))
    return run.finish("failed check")
