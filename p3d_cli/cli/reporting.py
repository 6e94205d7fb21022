"""A command's run over its inputs, as the command line shows it: outcomes in order, a
progress bar on a terminal, warnings and errors on stderr, a tally, a summary and an exit status.

The work itself runs in ``p3d_cli.batch`` (this process, forked workers or Dask); a command's
work function returns a ``Report``: its output, formatted where it was computed.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from typing import Callable, Generator

import click

from p3d_cli.batch import ClusterLost, Outcome, run_each
from p3d_cli.batch.inputs import collect, extension_counts
from p3d_cli.cli.main import error_message, exit_status, import_frozen
from p3d_cli.cli.output import one_line, shown_name
from p3d_cli.cli.reports import Entry, ReportOptions, prepare_reports, write_reports
from p3d_cli.errors import UsageError

#: Batches with more inputs than this get a progress bar, when stderr is a terminal.
PROGRESS_ABOVE = 5


@dataclass(frozen=True)
class Report:
    """One input's output, formatted where it was computed.

    Commands' work functions return this rather than result objects: a line of text crosses
    back from a worker process faster than pickled arrays, and the formatting is shared by
    the workers instead of queueing in the parent (which, for small files, cost as much as
    the work itself and kept ``--jobs 2`` from being much faster than ``--jobs 1``).

    Attributes
    ----------
    text : str or None
        For standard output (without its line end); None prints nothing.
    notes : tuple of str
        Whole lines for standard error, written above any progress bar.
    passed : bool
        False counts the input as failing a requirement (exit status 1).
    source : str or None
        The input, as reports name it.
    warnings : tuple of (code, text)
        Warnings not ignored: written to stderr as ``p3d: warning: [code] source: text``,
        counted (``warned``) and reported.
    failures : tuple of (code, text)
        Why the input failed a requirement, for reports (``--report``).
    """

    text: str | None = None
    notes: tuple[str, ...] = ()
    passed: bool = True
    source: str | None = None
    warnings: tuple[tuple[str, str], ...] = ()
    failures: tuple[tuple[str, str], ...] = ()


@dataclass(frozen=True)
class BatchOptions:
    """The shared batch options (``options.batch_options``) of one command invocation."""

    files_from: str | None = None
    jobs: int | None = None
    dask: str | None = None
    csv: bool = False
    null: bool = False
    reports: ReportOptions = ReportOptions()
    quiet: bool = False


class Batch:
    """One command's run over its inputs: outcomes, progress bar, tally, summary, exit status.

    Parameters
    ----------
    command : str
        ``p3d props``, ``p3d check``: names the command in usage errors.
    inputs : sequence of str
        The command's arguments.
    options : BatchOptions
    also_read : sequence of str
        Other files the command reads (``p3d diff``'s baseline): no report may overwrite them.

    Reports asked for are checked (none may overwrite an input) and marked incomplete here,
    before any input is read (``p3d_cli.cli.reports.prepare_reports``).
    """

    def __init__(self, command: str, inputs, options: BatchOptions, also_read=()) -> None:
        if options.dask is not None and options.jobs is not None:
            raise UsageError("--jobs/--dask", "both given",
                             "--dask runs on the cluster's workers; drop --jobs")
        self.command = command
        self.items, self.skipped = collect(inputs, options.files_from, command, null=options.null)
        self.options = options
        self.read = [*self.items, *also_read, *([options.files_from] if options.files_from else [])]
        if options.reports.wanted:
            prepare_reports(options.reports, command, self.read)
        self.ok = self.warned = self.failed = self.errors = 0
        self.status = 0
        self.entries: list[Entry] = []
        #: The error that ended the batch part way (a lost Dask scheduler), and how many
        #: inputs had their outcome by then.
        self.lost: ClusterLost | None = None
        self.done = 0
        self._bar = None
        self._started = time.monotonic()

    def note_settings(self, config, command: str, options: dict | None = None) -> None:
        """One stderr line naming the settings file, if any of its settings apply to an input
        (``p3d_cli.cli.settings.settings_for``); the text outputs' counterpart of JSON's
        ``settings`` key. Inconsistent settings are left for the inputs' own errors."""
        from p3d_cli.cli.settings import settings_for, settings_line
        from p3d_cli.errors import P3DError

        keys: dict[str, None] = {}
        for item in self.items:
            if isinstance(item, str):
                try:
                    used = settings_for(config, command, item, dict(options or {}))
                except P3DError:
                    continue
                keys.update(dict.fromkeys(used["keys"] if used else ()))
        if keys and not self.options.quiet:
            self.note(settings_line({"file": config.path, "keys": list(keys)}) or "")

    def outcomes(self, work: Callable[[str], object]) -> Generator[Outcome, None, None]:
        """``run_each`` over the inputs, with a progress bar on a terminal's stderr."""
        if self.options.dask is not None:
            import_frozen("dask.distributed")  # the client's import, ahead and faster (see there)
        results = run_each(self.items, work, jobs=self.options.jobs, dask=self.options.dask)
        self._bar = None if self.options.quiet else _progress_bar(len(self.items))
        try:
            for outcome in results:
                self.done += 1
                yield outcome
                if self._bar is not None:
                    self._bar.update(1)
        except ClusterLost as exc:   # every outcome that arrived is out; finish() counts the rest
            self.lost = exc
        finally:
            results.close()
            if self._bar is not None:
                self._bar.close()
                self._bar = None

    def report(self, work: Callable[[str], Report],
               error_text: Callable[[Outcome], str | None] = lambda outcome: None) -> None:
        """Run ``work`` over the inputs and write its reports in input order, as they come.

        An input that cannot be done is reported on stderr and counted, and ``error_text``
        (if it returns a line) gives its record on stdout. An error whose class has
        ``ends_batch`` set (a usage error only a result can reveal) ends the batch.
        """
        for outcome in self.outcomes(work):
            if outcome.error is not None:
                if outcome.error.ends_batch:
                    raise outcome.error
                self.error(outcome)
                text = error_text(outcome)
            else:
                report = outcome.result
                assert isinstance(report, Report)  # the command's work function returns one
                text = report.text
                self.record(report, outcome.source)
            if text is not None:
                self.out(text)

    def out(self, text: str) -> None:
        """One result on stdout. With a progress bar on the terminal that stdout also goes to,
        the bar is cleared first and drawn again below the line, so the two never share a line."""
        if self._bar is not None and _is_terminal(sys.stdout):
            self._bar.write(text, file=sys.stdout)
        else:
            click.echo(text)

    def record(self, report: Report, source: str) -> None:
        """Write a report's notes and warnings to stderr, and count and record its verdict."""
        source = report.source if report.source is not None else source
        for line in () if self.options.quiet else report.notes:
            self.note(line)
        for code, text in () if self.options.quiet else report.warnings:
            self.note(f"p3d: warning: [{code}] {shown_name(source)}: {text}")
        if not report.passed:
            self.fail()
            state = "failed"
        elif report.warnings:
            self.warned += 1
            state = "warned"
        else:
            self.passed()
            state = "ok"
        self.entries.append(Entry(source, state, report.failures, report.warnings))

    def note(self, text: str) -> None:
        """One line on stderr (written above the progress bar, if there is one)."""
        if self._bar is not None:
            self._bar.write(text, file=sys.stderr)
        else:
            click.echo(text, err=True)

    def error(self, outcome: Outcome) -> None:
        """Report an input that could not be done, and count it."""
        message = error_message(outcome.error)
        self.note(f"p3d: error: {one_line(message)}")
        self.errors += 1
        self.status = max(self.status, exit_status(outcome.error))
        self.entries.append(Entry(outcome.source, "errored", (("error", message),)))

    def passed(self) -> None:
        self.ok += 1

    def fail(self) -> None:
        """Count an input that was done but failed a requirement (exit status 1)."""
        self.failed += 1
        self.status = max(self.status, 1)

    @property
    def not_done(self) -> list[str]:
        """The inputs a batch ended part way (``lost``) did not reach, in input order."""
        if self.lost is None:
            return []
        return [item if isinstance(item, str) else item.where for item in self.items[self.done:]]

    def summary(self, failed_label: str = "failed check") -> str:
        n = max(len(self.items), len(self.entries))   # p3d diff adds the files that vanished
        parts = [f"{self.ok + self.warned} ok"]
        if self.failed:
            parts.append(f"{self.failed} {failed_label}")
        if self.errors:
            parts.append(f"{self.errors} error{'s' if self.errors != 1 else ''}")
        if self.lost is not None:
            parts.append(f"{len(self.not_done)} not done")
        line = f"{n} file{'s' if n != 1 else ''}: " + ", ".join(parts)
        if self.warned:
            codes: dict[str, int] = {}
            for entry in self.entries:
                if entry.state == "warned":
                    for code in dict.fromkeys(code for code, _ in entry.warnings):
                        codes[code] = codes.get(code, 0) + 1
            line += (f"; {self.warned} of the ok with warnings ("
                     + ", ".join(f"{code}: {count}" for code, count in codes.items()) + ")")
        if self.skipped:
            line += "; skipped files p3d does not read: " + extension_counts(self.skipped)
        return line

    def finish(self, failed_label: str = "failed check") -> int:
        """Print the summary (for more than one input, or when files were skipped), write the
        reports asked for, and return the exit status.

        The status is the worst seen: 3 a bug on some input, 2 some input could not be read,
        1 some input failed a requirement, 0 all passed.
        """
        if self.lost is not None:
            self.note(f"p3d: error: {one_line(error_message(self.lost))}")
            self.status = max(self.status, exit_status(self.lost))
            reason = (("not-done", f"not done: {self.lost.what}"),)
            self.entries += [Entry(source, "errored", reason) for source in self.not_done]
        if (len(self.items) > 1 or self.skipped or self.lost is not None) and not self.options.quiet:
            click.echo(f"p3d: {self.summary(failed_label)}", err=True)
        self.write_reports()
        return self.status

    def write_reports(self) -> None:
        """Write the reports asked for (replacing the incomplete ones written at the start)."""
        if self.options.reports.wanted:
            write_reports(self.options.reports, self.command, self.entries, self.skipped, self.status,
                          time.monotonic() - self._started, self.read)


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):   # no isatty, or a closed stream
        return False


def _progress_bar(total: int):
    """A tqdm bar on stderr when stderr is a terminal and the batch is big; else None (a pipe,
    a file, a CI log). Results on stdout go through ``Batch.out``, never onto the bar's line."""
    if total <= PROGRESS_ABOVE or not _is_terminal(sys.stderr):
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # tqdm is a dependency; a broken install loses the bar, nothing else
        return None
    # No monitor thread: a thread would make the worker pool avoid the fast fork start.
    tqdm.monitor_interval = 0
    return tqdm(total=total, file=sys.stderr, unit="file", leave=False, dynamic_ncols=True)
