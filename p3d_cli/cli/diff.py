"""``p3d diff``: compare meshes with a recorded baseline of their mass properties."""

from __future__ import annotations

import dataclasses
import functools
import json
import os

import click

from p3d_cli.cli import baseline as bl
from p3d_cli.cli import output
from p3d_cli.cli.main import error_message
from p3d_cli.cli.options import batch_options, density_options, format_option, json_option, warning_options
from p3d_cli.cli.props import props_report
from p3d_cli.cli.reporting import Batch, Report
from p3d_cli.errors import UsageError


@click.command()
@click.argument("baseline_file", metavar="BASELINE", type=click.Path(dir_okay=False))
@click.argument("inputs", nargs=-1, metavar="INPUT...", type=click.Path())
@format_option
@density_options
@click.option("--rtol", multiple=True, metavar="[QUANTITY=]REL",
              help="Relative tolerance (default 1e-9), for every quantity or one "
                   "(volume, mass, density, center_of_mass, inertia, principal_moments, bounds.min, "
                   "bounds.max). Repeatable.")
@click.option("--atol", multiple=True, metavar="[QUANTITY=]ABS",
              help="Absolute tolerance (default 0), for every quantity or one. Repeatable.")
@click.option("--root", type=click.Path(file_okay=False), default=None,
              help="Baseline paths are relative to this directory (default: the working directory).")
@click.option("--all", "whole_set", is_flag=True,
              help="The inputs are the whole set: every baseline entry not among them is reported "
                   "as vanished (by default only entries under a directory given as an input are).")
@click.option("--require", "require", multiple=True, metavar="CHECK[,CHECK...]",
              help="Also apply p3d check's checks (repeatable or comma-separated; all for every "
                   "check), on the same read of each file: the CI gate in one command. A failed "
                   "check is a change (quantity check:NAME).")
@click.option("--update", is_flag=True,
              help="Rewrite BASELINE with the current state of the inputs (exit 0); entries of "
                   "files not among the inputs are kept, unless they vanished.")
@json_option
@warning_options
@batch_options
def diff(baseline_file, inputs, fmt, density, mass, rtol, atol, root, whole_set, require, update, as_json, settings,
         batch):
    """Compare meshes with a baseline of their mass properties; exit 1 if anything changed.

    The baseline is the output of p3d props --json (one record per line), keyed by each
    file's path relative to --root, so that it works in any checkout. A change is a quantity
    that moved beyond |new - old| <= atol + rtol * scale (scale: the largest magnitude of the
    old value, of the whole vector or matrix), a different face count, a mesh that is no
    longer closed (or now is), a new warning code, a file that appeared, vanished or can no
    longer be read. A difference within the two results' stated rounding bounds (their
    uncertainty) is never a change; a flipped winding is a change of signed_volume. Each
    change is one line on stdout (--json: one record).

    The inputs may be a part of the baseline: an entry is reported as vanished only when it
    lies under a directory given as an input, or with --all (the inputs are the whole set).

    \b
    Examples:
      p3d props parts/ --json > baseline.ndjson
      p3d diff baseline.ndjson parts/
      p3d diff baseline.ndjson parts/ --rtol volume=1e-6 --report junit:p3d.xml
      git ls-files -z '*.stl' | p3d diff baseline.ndjson --files-from - -0 --all
      p3d diff baseline.ndjson parts/ --require all --report junit:gate.xml
      p3d diff baseline.ndjson parts/ --update

    With --require, each file is read once and both compared and checked (as p3d check
    --require would): the gate of a CI job in one command and one read.
    """
    if batch.csv:
        raise UsageError("--csv", "not an output of p3d diff", "use the default lines or --json")
    root = os.path.abspath(root or os.getcwd())
    limits = functools.partial(_tolerances, settings.config, rtol, atol)
    limits(None)   # refuse bad tolerances before any input is read
    run = Batch("p3d diff", inputs, batch, also_read=[baseline_file])
    if not as_json:
        run.note_settings(settings.config, "diff", {"density": density, "mass": mass, "units": None})
    if update:   # refused before any input is read: a baseline path that names one of the meshes
        from p3d_cli.io import atomic

        atomic.destination(baseline_file, inputs=[x for x in run.items if isinstance(x, str) and x != "-"],
                           what="the baseline")
    old = bl.read_baseline(baseline_file, root) if not (update and not os.path.exists(baseline_file)) else {}
    work = functools.partial(props_report, style="json", fields=(), strict=False, settings=settings,
                             density=density, mass=mass, format=fmt, placement=None, method="exact",
                             units=None)
    if require:
        from p3d_cli.cli.check import parse_require

        work = functools.partial(gate_report, work, parse_require(require))
    current: dict[str, dict] = {}
    for outcome in run.outcomes(work):
        if outcome.error is not None:
            if outcome.error.ends_batch:
                raise outcome.error
            record = {"source": outcome.source, "error": error_message(outcome.error)}
        else:
            assert isinstance(outcome.result, Report)
            record = json.loads(outcome.result.text or "{}")
        key = bl.baseline_key(outcome.source, root)
        current[key] = record
        changes = bl.compare(key, old[key], record, *limits(outcome.source)) if key in old else \
            [bl.Change(key, "file", None, "appeared")]
        if isinstance(outcome.result, Report):   # with --require: the checks that failed
            changes += [bl.Change(key, f"check:{name}", None, text) for name, text in outcome.result.failures]
        _report(run, key, changes, as_json)
    if run.lost is not None:   # a batch ended part way: what vanished is unknown; the baseline stays
        return run.finish("changed")
    searched = [bl.baseline_key(x, root) for x in inputs if x != "-" and os.path.isdir(x)]
    vanished = [key for key in old if key not in current and (whole_set or bl.covered(key, searched))]
    for key in vanished:
        _report(run, key, [bl.Change(key, "file", "present", "vanished")], as_json)
    if update:
        kept = {key: record for key, record in old.items() if key not in current and key not in vanished}
        _write_baseline(baseline_file, {**kept, **current}, root, run.items)
        run.status = 0
    return run.finish("changed")


def gate_report(work, require: tuple[str, ...], source) -> Report:
    """``work`` (the props record of ``source``) and ``p3d check``'s verdict on the same read of
    the file: the mesh is loaded once and both are measured from it. Failed checks come back
    as the report's ``failures``. A shape spec is a clean solid by construction (not checked);
    an assembly file is checked part by part (``p3d_cli.measure.assembly.check``)."""
    from p3d_cli import measure
    from p3d_cli.cli.check import failure_messages
    from p3d_cli.measure import names_assembly_file
    from p3d_cli.shapes import parse_spec

    fmt = work.keywords.get("format")
    thing = source
    if source == "-" or (parse_spec(source) is None and (fmt is not None or not names_assembly_file(source))):
        from p3d_cli.io import load_mesh

        thing = load_mesh(source, fmt)
    report = work(thing)
    if parse_spec(source) is not None:
        return report
    verdict = measure.check(thing, require=require)
    return dataclasses.replace(report, passed=verdict.ok, failures=failure_messages(verdict))


def _tolerances(config, rtol, atol, source: str | None) -> tuple[dict, dict]:
    """``(rtol, atol)`` per quantity for ``source``: p3d's defaults, then the project settings
    (the top level, then the matching ``[[paths]]``), then the command line."""
    settings = config.settings if source is None else config.for_source(source)
    out = []
    for name, given, default in (("rtol", rtol, bl.QUANTITIES), ("atol", atol, dict.fromkeys(bl.QUANTITIES, 0.0))):
        if settings.get(name) is not None:   # a setting's errors name the file and the key
            default = bl.tolerances([settings[name]], default, config.where(name, source))
        out.append(bl.tolerances(given, default, f"--{name}"))
    return out[0], out[1]


def _report(run: Batch, key: str, changes: list, as_json: bool) -> None:
    for change in changes:
        run.out(output.formatted("diff", change.record(), "json") if as_json else change_line(change))
    failures = tuple((c.quantity, change_line(c)) for c in changes)
    run.record(Report(passed=not changes, source=key, failures=failures), key)


def change_line(change: bl.Change) -> str:
    """``parts/a.stl: volume 1 -> 1.0003 (+0.03%)``; a vector or matrix by the component that
    moved most, ``inertia[1,1]``, with its quantity's relative change."""
    name = output.shown_name(change.source)
    if change.quantity == "file":
        what = {"appeared": "appeared (not in the baseline)", "vanished": "vanished (in the baseline, not found)",
                "read": "can be read again"}.get(change.new, f"cannot be read now: {change.new}")
        if change.old not in (None, "present", "read") and change.new == "read":
            what = "can be read now (the baseline has an error)"
        return f"{name}: {what}"
    if change.quantity.startswith("check:"):     # --require: the check's own sentence
        return f"{name}: {change.new}"
    quantity, old, new = change.quantity, change.old, change.new
    if isinstance(old, list) and isinstance(new, list) and _shape(old) == _shape(new) and old:
        # A vector or matrix: the component that moved most stands for it (the JSON has all).
        index = max(_indices(old), key=lambda i: abs(_at(new, i) - _at(old, i)))
        quantity = f"{quantity}[{','.join(map(str, index))}]"
        old, new = _at(old, index), _at(new, index)
    return f"{name}: {quantity} {_value(old)} -> {_value(new)}{_relative(change.relative)}"


def _shape(value) -> tuple:
    return (len(value),) + _shape(value[0]) if isinstance(value, list) and value else ()


def _indices(value, prefix: tuple = ()) -> list[tuple]:
    if isinstance(value, list):
        return [i for k, v in enumerate(value) for i in _indices(v, prefix + (k,))]
    return [prefix]


def _at(value, index: tuple):
    for k in index:
        value = value[k]
    return value


def _value(value) -> str:
    """A JSON value for the change line: numbers to 10 digits, vectors and matrices bracketed."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return output.dumps(value)
    if isinstance(value, (int, float)):
        return output.number(value)
    if isinstance(value, list) and all(isinstance(x, (int, float, list)) for x in value):
        return "[" + ", ".join(_value(x) for x in value) + "]"
    return output.dumps(value)


def _relative(relative) -> str:
    if relative is None:
        return ""
    return f" ({relative * 100:+.3g}%)"


def _write_baseline(path: str, records: dict[str, dict], root: str, inputs=()) -> None:
    """The baseline, replaced whole (``p3d_cli.io.atomic``): a full disk or a kill part way leaves
    the old one; never written over one of the meshes."""
    from p3d_cli.io import atomic

    text = "".join(output.formatted("props", {**record, "source": key}, "json") + "\n"
                   for key, record in sorted(records.items()))
    atomic.write_bytes(path, text.encode("utf-8", "surrogateescape"),
                       inputs=[x for x in inputs if isinstance(x, str) and x != "-"], what="the baseline")
