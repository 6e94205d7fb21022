"""``p3d repair``: fix what ``check`` finds, change nothing else, and say every change."""

from __future__ import annotations

import functools
import os

import click

from p3d_cli.cli import output
from p3d_cli.cli.check import parse_require
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import FiniteFloat, batch_options, format_option, inputs_argument, json_option
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.errors import OutputError, UsageError
from p3d_cli.repairs.fill import FLATNESS, MAX_EDGES, POLICIES
from p3d_cli.repairs.report import SHOWN, RepairReport, StepReport
from p3d_cli.repairs.steps import STEPS

#: Notes of a step shown in the text report.
NOTES_SHOWN = 3

def repair_report(source: str, *, style: str, targets: dict, **options) -> Report:
    """One input repaired and its report formatted (module level: workers receive it)."""
    from p3d_cli.repairs import repair_file

    target = targets.get(source)
    if isinstance(target, OutputError):
        raise target
    report = repair_file(source, target, **options)
    text = output.formatted("repair", report.to_dict(), style) if style in output.STYLES else repair_text(report)
    failures = tuple(("not-fixed", line) for line in report.unfixed)
    if not report.within_limit:
        failures += (("max-volume-change", f"the volume changed by {report.mass.relative_volume_change:.3g} "
                      f"(relative), over the limit {report.max_volume_change:g}: nothing written"),)
    return Report(text, passed=report.ok, source=source, failures=failures)

def error_line(outcome, *, style: str) -> str | None:
    """The record of an input that could not be done (JSON or CSV; nothing in text)."""
    return output.failed("repair", outcome.source, error_message(outcome.error), style, ok=False)

def repair_text(report: RepairReport) -> str:
    """The human report of one repair."""
    name = output.shown_name(report.source)
    verdict = ("fixed" if report.changed else "ok, nothing to repair") if report.fixed else "NOT FIXED"
    if not report.within_limit:
        verdict += ", over the volume limit"
    where = f" -> {output.shown_name(report.output)}" if report.output and report.output != report.source else ""
    lines = [f"{name}{where}: {verdict} ({_written(report)})"]
    lines.append(f"  before: {_verdict(report.failed_before, report.before)}")
    if report.failed_before:             # a mesh check passes runs no step: nothing to say of them
        for step in report.steps:
            text = _step_text(step)
            if text:
                lines.append(f"  {step.name}: {text}")
        lines.append(f"  after: {_verdict(report.failed_after, report.after)}")
    lines.append("  " + _mass_text(report))
    for line in report.unfixed:
        lines.append(f"  not fixed: {line}")
    for note in report.notes:
        lines.append(f"  note: {note}")
    return "\n".join(lines)

def _written(report: RepairReport) -> str:
    return {"written": "written", "copied": "copied unchanged", "not written": "nothing written: not needed",
            "unchanged": "left unchanged", "refused": "nothing written", "dry run": "dry run: nothing written",
            "": "not written"}.get(report.written, report.written)

def _verdict(failed: tuple[str, ...], topology) -> str:
    head = "passes p3d check" if not failed else "fails " + ", ".join(failed)
    return f"{head} ({output.plural(topology.faces, 'face')}, {output.plural(topology.shells, 'shell')})"

def _faces(numbers, noun: str = "face") -> str:
    shown = ", ".join(str(f) for f in numbers[:SHOWN])
    more = f", ... ({len(numbers) - SHOWN} more)" if len(numbers) > SHOWN else ""
    return f"{noun}{'s' if len(numbers) != 1 else ''} {shown}{more}"

def _step_text(step: StepReport) -> str:
    """One line for a step (empty for a step not asked for that left no note)."""
    if not step.ran:
        return "; ".join(step.notes) if step.notes else ""
    c = step.counts
    parts = []
    if step.name == "weld":
        parts.append(f"{output.plural(c['vertices_merged'], 'vertex')} merged (within {c['tolerance']:g}, largest "
                     f"distance {c['largest_distance']:.3g}), {output.plural(c['faces_moved'], 'face')} moved")
        if step.faces:
            parts[-1] += f" ({_faces(step.faces)})"
    elif step.name in ("degenerate", "duplicate"):
        removed = c.get("faces_removed", 0)
        parts.append(f"{output.plural(removed, 'face')} removed" + (f" ({_faces(step.faces)})" if removed else ""))
    elif step.name == "orient":
        flipped = c.get("faces_flipped", 0)
        parts.append(f"{output.plural(flipped, 'face')} flipped" + (f" in {output.plural(c['shells'], 'shell')} "
                                                             f"({_faces(step.faces)})" if flipped else ""))
    elif step.name == "holes":
        filled, left = c.get("holes_filled", 0), c.get("holes_left", 0)
        added = f" with {output.plural(c['faces_added'], 'new face')} ({_faces(step.new_faces)})" if filled else ""
        parts.append(f"{output.plural(filled, 'hole')} filled{added}")
        if c.get("faces_split"):
            parts.append(f"{output.plural(c['faces_split'], 'face')} split at a T-junction ({_faces(step.faces)})")
        if left:
            parts.append(f"{left} left")
    elif step.name == "outward":
        flipped = c.get("shells_flipped", 0)
        faces = f" ({output.plural(c['faces_flipped'], 'face')})" if flipped else ""
        parts.append(f"{output.plural(flipped, 'shell')} flipped{faces}")
        if c.get("cavities"):
            parts.append(f"{output.plural(c['cavities'], 'cavity')} kept wound inward")
    text = "; ".join(parts)
    for note in step.notes[:NOTES_SHOWN]:
        text += f"\n    {note}"
    if len(step.notes) > NOTES_SHOWN:
        text += "\n    and more like these (--json lists them)"
    return text

def _mass_text(report: RepairReport) -> str:
    m = report.mass
    change = m.relative_volume_change
    text = (f"volume {output.number(m.before.volume)} -> {output.number(m.after.volume)} "
            f"(relative change {change:.3g})")
    if m.center_shift is not None and m.center_shift:
        text += f"; centre of mass moved {output.number(m.center_shift, 4)}"
    if m.relative_inertia_change:
        text += f"; inertia changed {m.relative_inertia_change:.3g} (relative)"
    return text

def output_targets(inputs, items, out: str | None, output_format: str | None) -> tuple[dict, bool]:
    """The output of every input (None: in place or a dry run), and whether they mirror the
    inputs into a folder (one file when there is one input and ``out`` is no folder)."""
    from p3d_cli.repairs.destinations import mirrored

    names = [item for item in items if isinstance(item, str)]
    if out is None:
        return {name: None for name in names}, False
    if out == "-":
        raise UsageError("--output", "standard output holds the report", "give the repaired mesh a file path")
    if not out:
        raise UsageError("--output", "an empty path", "give a file path, or a folder for several inputs")
    folder = (os.path.isdir(out) or out.endswith(("/", os.sep)) or len(items) > 1
              or any(os.path.isdir(i) for i in inputs if i != "-"))
    if not folder:
        return {name: out for name in names}, False
    if os.path.exists(out) and not os.path.isdir(out):
        many = "there are several inputs" if len(items) > 1 else "the input is a folder"
        raise UsageError("--output", f"{out} is a file, but {many}", "give a folder to mirror them into")
    extension = None
    if output_format is not None:
        from p3d_cli.io.writers import output_format as format_of

        extension = "." + format_of(out, output_format)
    return mirrored(names, [i for i in inputs if i != "-" and os.path.isdir(i)], out, extension), True

@click.command()
@inputs_argument
@click.option("-o", "--output", "out", default=None, metavar="PATH",
              help="Write the repaired mesh here (format from the extension: .stl binary, .ply, .obj, "
                   ".off); with several inputs or a folder, a folder mirroring the inputs' tree.")
@click.option("--in-place", is_flag=True, help="Replace each input with its repair (atomically), in its own format.")
@click.option("--dry-run", is_flag=True, help="Report what would change; write nothing.")
@click.option("--only-if-needed", is_flag=True,
              help="Write nothing for a mesh that needs no repair (default: copy it unchanged).")
@click.option("--output-format", type=click.Choice(["stl", "ply", "obj", "off"]), default=None,
              help="Write this format whatever the output's extension.")
@click.option("--steps", "steps", multiple=True, metavar="STEP[,STEP...]",
              help="Steps to run: " + ", ".join(STEPS) + "; all (the default), none; -STEP leaves one out.")
@click.option("--weld", type=FiniteFloat(positive=True), default=None, metavar="TOL",
              help="First merge vertices closer than TOL (mesh units); default: exact matching only.")
@click.option("--fill-holes", type=click.Choice(POLICIES), default="flat", show_default=True,
              help="flat: fill loops flat within --flatness with at most --max-hole-edges edges; "
                   "any: every loop that is simple seen along its normal.")
@click.option("--flatness", type=FiniteFloat(), default=FLATNESS, show_default=True, metavar="F",
              help="Largest distance of a hole's corner from its plane, as a fraction of the hole's size.")
@click.option("--max-hole-edges", type=click.IntRange(min=3), default=MAX_EDGES, show_default=True, metavar="N",
              help="Largest hole (in edges) --fill-holes flat fills.")
@click.option("--max-volume-change", type=FiniteFloat(), default=None, metavar="R",
              help="Fail (exit 1, nothing written) when the volume changes by more than R, relative.")
@click.option("--require", "require", multiple=True, metavar="CHECK[,CHECK...]",
              help="The checks of p3d check that decide what needs repair and what is fixed (as p3d check "
                   "--require; default all). Leaving out no-self-intersection,nesting skips the self-intersection "
                   "test.")
@format_option
@json_option
@batch_options
def repair(inputs, out, in_place, dry_run, only_if_needed, output_format, steps, weld, fill_holes, flatness,
           max_hole_edges, max_volume_change, require, fmt, as_json, batch):
    """Repair meshes: fix what p3d check finds, change nothing else, say every change.

    The steps run in this order, each only where check found something: weld (only with
    --weld), degenerate (remove zero-area faces), duplicate (remove repeated faces), orient
    (flip the faces that disagree with the rest of their shell), holes (fill holes bounded by
    simple, flat loops with triangles of their own corners), outward (flip whole closed
    shells outward, shells inside shells as cavities). Faces not touched are written with
    their coordinates bit for bit; a mesh check passes is copied unchanged; every output is
    checked by check's own code. What repair cannot fix (non-manifold edges and vertices,
    holes it leaves, faces that cross) is listed, and the exit status is 1. Each step's
    counts and face numbers, and the volume, centre of mass and inertia before and after,
    are reported (--json: one record per input).

    \b
    Exit statuses:
      0  every output passes p3d check (the --require checks; and --max-volume-change holds)
      1  some mesh is not fixed, or changed more than --max-volume-change
      2  usage error, or an input cannot be read or an output written (the batch goes on)
      3  a bug in p3d met on some input (please report it)

    \b
    Examples:
      p3d repair part.stl -o fixed.stl
      p3d repair part.stl -o fixed.stl --max-volume-change 1e-6 --json
      p3d repair scans/ -o repaired/ --fill-holes any --jobs 4
      p3d repair part.obj --in-place --steps -holes
      p3d repair part.stl --dry-run
    """
    modes = [flag for flag, on in (("-o/--output", out is not None), ("--in-place", in_place),
                                   ("--dry-run", dry_run)) if on]
    if len(modes) != 1:
        raise UsageError("p3d repair", "both " + " and ".join(modes) if modes else "no output given",
                         "give one of -o PATH, --in-place or --dry-run")
    style = "json" if as_json else "csv" if batch.csv else "text"
    if as_json and batch.csv:
        raise UsageError("--json/--csv", "both given", "give one")
    run = Batch("p3d repair", inputs, batch)
    targets, mirror = output_targets(inputs, run.items, out, output_format)
    required = parse_require(require) if require else None        # None: every check
    work = functools.partial(repair_report, style=style, targets=targets, in_place=in_place, require=required,
                             only_if_needed=only_if_needed, output_format=output_format,
                             max_volume_change=max_volume_change, steps=steps or None, weld=weld,
                             fill_holes=fill_holes, flatness=flatness, max_hole_edges=max_hole_edges,
                             format=fmt, create_folders=mirror)
    if batch.csv:
        click.echo(output.csv_header("repair"))
    run.report(work, functools.partial(error_line, style=style))
    return run.finish("not fixed")
