"""``p3d check``: is each mesh a clean, closed, outward-facing solid? One verdict per file."""

from __future__ import annotations

import functools

import click

from p3d_cli import measure
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import (
    FiniteFloat,
    batch_options,
    config_option,
    field_option,
    format_option,
    inputs_argument,
    json_option,
)
from p3d_cli.cli.output import plural
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.cli.settings_file import Config
from p3d_cli.errors import UsageError
from p3d_cli.mesh.verdicts import CHECKS, SAMPLED_COUNTS as _COUNTS, CheckResult, check_record

def check_report(source: str, *, style: str, fields: tuple[str, ...] = (), config: Config | None = None,
                 **limits) -> Report:
    """One input's verdict in ``style`` (text, json, csv or fields), formatted where it was
    computed (module level, so that worker processes can receive it). Without ``require``, the
    project settings' ``require`` for the input applies (default: every check)."""
    used = None
    if limits.get("require") is None:
        config = config or Config()
        limits["require"] = parse_require(tuple(config.get("require", source, ())),
                                          where=config.where("require", source))
        used = config.used("check", source)
    result = measure.check(source, **limits)
    if style == "text":
        text = check_text(result)
    else:
        record = check_record(result)
        record["settings"] = used
        text = output.formatted("check", record, style, fields)
    return Report(text, passed=result.ok, source=result.source, failures=failure_messages(result))


def failure_messages(result: CheckResult) -> tuple[tuple[str, str], ...]:
    """``(check, message)`` for each failed check, for CI reports."""
    r = result.report
    counts = {"closed": plural(r.boundary_edges, "boundary edge"),
              "oriented": plural(r.misoriented_edges, "misoriented edge"),
              "manifold": f"{plural(r.nonmanifold_edges, 'non-manifold edge')}, "
                          f"{plural(r.nonmanifold_vertices, 'non-manifold vertex')}",
              "no-degenerate": plural(r.degenerate_faces, "degenerate face"),
              "no-duplicate": plural(r.duplicate_faces, "duplicate face"),
              "no-self-intersection": plural(_crossing_count(r), "self-intersecting face pair"),
              "nesting": _nesting_detail(r)}
    out = []
    for name in result.failed:
        if name == "min-volume":
            text = f"signed volume {output.number(r.volume)} is below the min-volume limit"
        elif name == "max-faces":
            text = f"{plural(r.faces, 'face')}: over the max-faces limit"
        elif name == "outward":
            text = f"signed volume {output.number(r.volume)} is not positive (faces point inward)"
        else:
            detail = f" ({counts[name]})" if name in counts else ""
            text = f"fails the {name} check{detail}: {CHECKS.get(name, name)}"
        out.append((name, text))
    return tuple(out)


def error_line(outcome, *, style: str) -> str | None:
    """The record of an input that could not be read: JSON or CSV, an empty line for --field;
    nothing in text style."""
    return output.failed("check", outcome.source, error_message(outcome.error), style, ok=False)


def parse_require(values: tuple[str, ...], where: str = "--require") -> tuple[str, ...]:
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
                raise UsageError(where, f"no check named {name!r}",
                                 "checks are: " + ", ".join(CHECKS) + " (or all, none)")
    return tuple(dict.fromkeys(names))


#: Digits of the coordinates of problem locations in the text verdict (enough to find them).
LOCATION_DIGITS = 7


def check_text(result: CheckResult) -> str:
    """A readable verdict for one input: 80 columns (a long file name aside), with sample
    locations of each problem one per line."""
    r = result.report
    head = "ok" if result.ok else "FAILED " + ", ".join(result.failed)
    name = output.shown_name(result.source)
    unit = " m^3" if result.declared_unit else ""
    details = (f"({result.format}, {plural(r.faces, 'face')}, {plural(r.shells, 'shell')}, "
               f"volume {output.number(r.solid_volume)}{unit})")
    lines = [f"{name}: {head}  {details}"]
    if len(lines[0]) > 80 and len(name) <= 40:
        # Break before the details when that makes the verdict fit; a name too long for any
        # layout to fit keeps its verdict on one line, which greps better.
        lines = [f"{name}: {head}", f"  {details}"]
    if result.weld is not None:
        w = result.weld
        lines.append(f"  welded {w.vertices} {'vertex' if w.vertices == 1 else 'vertices'} within "
                     f"{output.number(w.tolerance)} (largest distance {output.number(w.largest_distance)})")
    for key, noun, samples in _COUNTS:
        count = getattr(r, key)
        if count:
            head = f"  {count} {noun}{'s' if count != 1 else ''}"
            listed = [_sample_text(sample) for sample in getattr(r, samples)]
            lines += _pack(head + " (e.g. ", listed, ")") if listed else [head]
    lines += _crossing_lines(r) + _nesting_lines(r)
    if r.volume < 0:
        lines += _fit(f"signed volume {output.number(r.volume)}{unit} is negative: faces point inward (reverse the "
                      "winding); the volume shown is the enclosed solid's, as p3d props reports it", "  ")
    elif r.volume == 0:
        lines += _fit("signed volume is 0: the mesh encloses nothing", "  ")
    if r.shells > 1:
        lines.append("  shell volumes:")
        for s in r.shell_list[:10]:
            lines.append(f"    {output.number(s.volume)} ({plural(s.faces, 'face')} from face {s.first_face})")
        if r.shells > 10:
            lines.append(f"    and {r.shells - 10} more")
    for name in ("min-volume", "max-faces"):
        if name in result.failed:
            lines.append("  over the max-faces limit" if name == "max-faces" else "  below the min-volume limit")
    for _, part in result.parts:
        lines += ["  " + line for line in check_text(part).splitlines()]
    return "\n".join(lines)


def _nesting_detail(report) -> str:
    """``volume counted twice: 1, negative: 0, crossing shells: 1`` for the failure message."""
    n = report.nesting
    if n is None:
        return "not tested"
    crossing = sum(1 for _, _, kind in n.relations if kind == "crossing")
    return (f"volume counted twice: {output.number(n.counted_twice)}, negative: "
            f"{output.number(n.counted_negative)}, {plural(crossing, 'pair')} of crossing shells")


def _crossing_count(report) -> int:
    found = report.self_intersections
    return 0 if found is None else found.count


def _crossing_lines(report) -> list[str]:
    """``  3 self-intersecting face pairs (e.g. faces 2,17 cross at (x, y, z); ...)``."""
    found = report.self_intersections
    if found is None or not found.count:
        return []
    verbs = {"crossing": "cross", "overlap": "overlap", "fold": "fold"}
    listed = [f"faces {a},{b} {verbs[c.kind]} at {_point(c.point)}" for c, (a, b) in
              ((c, c.faces) for c in found.samples)]
    head = f"  {plural(found.count, 'self-intersecting face pair')}"
    return _pack(head + " (e.g. ", listed, ")")


def _nesting_lines(report) -> list[str]:
    """What is wrong with how the closed shells nest, and the volume it miscounts."""
    nesting = report.nesting
    if nesting is None or nesting.ok:
        return []
    places = {p.shell: p for p in nesting.shells}

    def shell(s: int) -> str:
        p = places.get(s)
        return f"shell {s}" + (f" ({plural(p.faces, 'face')} from face {p.first_face})" if p else "")

    out = []
    for a, b, kind in nesting.relations:
        if kind == "crossing":
            out.append(f"{shell(a)} and {shell(b)} cross")
        elif kind == "coincident":
            out.append(f"{shell(a)} lies on the surface of {shell(b)}")
    for p in nesting.shells:
        if p.inside is not None and abs(p.winding) >= 2:
            out.append(f"{shell(p.shell)} lies inside {shell(p.inside)} and is wound alike: "
                       f"its volume is counted {abs(p.winding)} times")
        elif p.winding * (1 if report.volume >= 0 else -1) < 0:
            out.append(f"{shell(p.shell)} is wound as a cavity but lies in no body: its volume is counted negative")
    lines = [line for text in out for line in _fit(text, "  ")]
    miscount = []
    if nesting.counted_twice or nesting.crossing_bound:
        exact = output.number(nesting.counted_twice)
        bound = (f" + at most {output.number(nesting.crossing_bound)} where shells cross"
                 if nesting.crossing_bound else "")
        miscount.append(f"volume counted twice: {exact}{bound}")
    if nesting.counted_negative:
        miscount.append(f"volume counted negative: {output.number(nesting.counted_negative)}")
    return lines + [line for text in miscount for line in _fit(text, "  ")]


def _fit(text: str, indent: str, width: int = 80) -> list[str]:
    """``text`` as lines of at most ``width`` columns, each starting with ``indent`` (the
    continuation lines two spaces further in); breaks only at spaces."""
    import textwrap

    return textwrap.wrap(text, width, initial_indent=indent, subsequent_indent=indent + "  ",
                         break_long_words=False, break_on_hyphens=False) or [indent]


def _pack(head: str, items: list[str], tail: str, indent: str = "    ", width: int = 80) -> list[str]:
    """``head`` + items joined by ``; `` + ``tail``, broken between items to fit ``width`` (an
    edge too long for a line of its own is broken between its two end points)."""
    pieces = []
    for i, item in enumerate(items):
        text = item + (tail if i == len(items) - 1 else ";")
        if len(indent) + len(text) > width and ")-(" in text:
            first, rest = text.split(")-(", 1)
            pieces += [first + ")-", "  (" + rest]
        else:
            pieces.append(text)
    lines, line = [], head
    for piece in pieces:
        if len(line) + len(piece) > width and line.strip():
            lines.append(line.rstrip())
            line = indent
        line += piece + " "
    return [ln for ln in lines + [line.rstrip()] if ln.strip()]


def _point(p) -> str:
    return "(" + ", ".join(output.number(x, LOCATION_DIGITS) for x in p) + ")"


def _sample_text(sample) -> str:
    if isinstance(sample, int):
        return f"face {sample}"
    if isinstance(sample, tuple):
        return f"face {sample[1]} repeats face {sample[0]}"
    faces = "face" + ("s " if len(sample.faces) != 1 else " ") + ",".join(map(str, sample.faces))
    if hasattr(sample, "points"):
        a, b = (_point(p) for p in sample.points)
        return f"{faces} at {a}-{b}"
    return f"{faces} at {_point(sample.point)}"


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
@click.option("--weld", type=FiniteFloat(), default=None, metavar="TOL",
              help="Merge vertices closer than TOL (in the file's units) before checking, and say how "
                   "many and how far apart they were (never done without it).")
@json_option
@field_option
@config_option
@batch_options
def check(inputs, fmt, require, min_volume, max_faces, as_json, fields, config, batch, weld=None):
    """Check that meshes are clean solids: one verdict per file, and an exit status.

    Each mesh is checked for being closed (every edge used by exactly two faces, in
    opposite directions), consistently oriented, outward-facing (positive signed volume),
    manifold (no edge used by more than two faces, no vertex joining separate fans), free
    of degenerate (zero-area or repeated-vertex) and duplicate faces, and free of
    self-intersections (no two faces whose interiors cross or overlap, decided with exact
    arithmetic: faces that share an edge or a vertex, or only touch, never count). Its
    connected shells are counted, each with its signed volume. Each problem comes with its
    count and a few locations (face indices from 0, edge end points, a point on each
    crossing). Vertices are matched by exact coordinates: nothing is merged within a
    tolerance. Every check is O(n log n); the self-intersection test is the costliest
    (--require without no-self-intersection skips it).

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
      p3d check scan.stl --weld 1e-6
    """
    required = parse_require(require) if require else None   # None: the settings', or all
    style = output.output_style(as_json, batch.csv, fields, "text")
    run = Batch("p3d check", inputs, batch)
    if weld is not None and not weld > 0:
        raise UsageError("--weld", f"{weld} is not positive", "give the largest distance of vertices to merge")
    if style in ("text", "fields") and required is None:
        run.note_settings(config, "check")
    work = functools.partial(check_report, style=style, fields=fields, config=config, format=fmt,
                             require=required, min_volume=min_volume, max_faces=max_faces,
                             **({"weld": weld} if weld is not None else {}))
    if batch.csv:
        click.echo(output.csv_header("check"))
    run.report(work, functools.partial(error_line, style=style))
    return run.finish("failed check")
