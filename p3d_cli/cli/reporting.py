"""A command's run over its inputs, as the command line shows it: outcomes in order, a
progress bar on a terminal, warnings and errors on stderr, a tally, a summary and an exit status.

The work itself runs in ``p3d_cli.batch`` (this process, forked workers or Dask); a command's
work function returns a ``Report``: its output, formatted where it was computed.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from typing import Callable, Generator

import click

from p3d_cli.batch import Outcome, collect_inputs, run_each
from p3d_cli.cli.main import error_message, exit_status
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
        Whole lines for standard error (warnings), written above any progress bar.
    passed : bool
        False counts the input as failing a requirement (exit status 1).
    """

    text: str | None = None
    notes: tuple[str, ...] = ()
    passed: bool = True


@dataclass(frozen=True)
class BatchOptions:
    """The shared batch options (``options.batch_options``) of one command invocation."""

    files_from: str | None = None
    jobs: int | None = None
    dask: str | None = None
    csv: bool = False


class Batch:
    """One command's run over its inputs: outcomes, progress bar, tally, summary, exit status.

    Parameters
    ----------
    command : str
        ``p3d props``, ``p3d check``: names the command in usage errors.
    inputs : sequence of str
        The command's arguments.
    options : BatchOptions
    """

    def __init__(self, command: str, inputs, options: BatchOptions) -> None:
        if options.dask is not None and options.jobs is not None:
            raise UsageError("--jobs/--dask", "both given",
                             "--dask runs on the cluster's workers; drop --jobs")
        self.items = collect_inputs(inputs, options.files_from, command)
        self.options = options
        self.ok = self.failed = self.errors = 0
        self.status = 0
        self._bar = None

    def outcomes(self, work: Callable[[str], object]) -> Generator[Outcome, None, None]:
        """``run_each`` over the inputs, with a progress bar on a terminal's stderr."""
        results = run_each(self.items, work, jobs=self.options.jobs, dask=self.options.dask)
        self._bar = _progress_bar(len(self.items))
        try:
            for outcome in results:
                yield outcome
                if self._bar is not None:
                    self._bar.update(1)
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
                for line in report.notes:
                    self.note(line)
                self.passed() if report.passed else self.fail()
                text = report.text
            if text is not None:
                click.echo(text)

    def note(self, text: str) -> None:
        """One line on stderr (written above the progress bar, if there is one)."""
        if self._bar is not None:
            self._bar.write(text, file=sys.stderr)
        else:
            click.echo(text, err=True)

    def error(self, outcome: Outcome) -> None:
        """Report an input that could not be done, and count it."""
        self.note(f"p3d: error: {error_message(outcome.error)}")
        self.errors += 1
        self.status = max(self.status, exit_status(outcome.error))

    def passed(self) -> None:
        self.ok += 1

    def fail(self) -> None:
        """Count an input that was done but failed a requirement (exit status 1)."""
        self.failed += 1
        self.status = max(self.status, 1)

    def summary(self, failed_label: str = "failed check") -> str:
        n = len(self.items)
        parts = [f"{self.ok} ok"]
        if self.failed:
            parts.append(f"{self.failed} {failed_label}")
        if self.errors:
            parts.append(f"{self.errors} error{'s' if self.errors != 1 else ''}")
        return f"{n} file{'s' if n != 1 else ''}: " + ", ".join(parts)

    def finish(self, failed_label: str = "failed check") -> int:
        """Print the summary (for more than one input) and return the exit status.

        The status is the worst seen: 3 a bug on some input, 2 some input could not be read,
        1 some input failed a requirement, 0 all passed.
        """
        if len(self.items) > 1:
            click.echo(f"p3d: {self.summary(failed_label)}", err=True)
        return self.status


def _progress_bar(total: int):
    """A tqdm bar on stderr when stderr is a terminal and the batch is big; else None."""
    if total <= PROGRESS_ABOVE or not sys.stderr.isatty():
        return None
    try:
        from tqdm import tqdm
    except ImportError:  # optional extra (p3d-cli[progress]): no bar, nothing else changes
        return None
    # No monitor thread: a thread would make the worker pool avoid the fast fork start.
    tqdm.monitor_interval = 0
    return tqdm(total=total, file=sys.stderr, unit="file", leave=False, dynamic_ncols=True)
