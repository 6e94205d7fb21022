"""Running one command over many inputs: in order, in processes or on a Dask cluster.

Inputs are the command's arguments (files, directories searched for mesh files, ``-`` for
standard input) followed by the lines of ``--files-from LIST`` (``p3d_cli.cli.inputs``).
Every input yields exactly one ``Outcome``, in input order, as soon as it and every input
before it are done: a failing input yields an error outcome and the batch goes on.

Where the work runs:

- in this process, when there is one input or ``--jobs 1`` (no start-up cost);
- in ``--jobs N`` worker processes on this machine, in chunks, results in order: forked
  workers (``p3d_cli.cli.workers``), or ``multiprocessing.Pool`` where fork is unsafe; the
  default is the number of cores this process may use;
- on an existing Dask cluster with ``--dask ADDRESS`` (optional extra ``p3d-cli[dask]``;
  the workers need p3d installed and must see the same paths).

Standard input is always read here, at its turn. The work function may be sent to other
processes (Dask, or a pool started by spawn), so it must be picklable: a module-level
function, or a ``functools.partial`` of one with picklable arguments. Its results are
pickled back: commands return short ``Report`` texts rather than arrays.

A bug met while working on one input (an exception that is not a ``P3DError``) becomes an
error outcome with exit status 3 rather than ending the batch; ``P3D_DEBUG=1`` re-raises it
(in a forked worker: its traceback is shown and the input is reported as not done).
"""

from __future__ import annotations

import functools
import importlib
import os
import signal
import sys
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator

import click

from p3d_cli.cli.inputs import collect_inputs, expand_inputs
from p3d_cli.errors import InputError, MissingExtraError, P3DError, UsageError

#: Batches with more inputs than this get a progress bar, when stderr is a terminal.
PROGRESS_ABOVE = 5

EXIT_INTERNAL = 3


@dataclass(frozen=True)
class Outcome:
    """One input's result or its error."""

    source: str
    result: object = None
    error: P3DError | None = None


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


def default_jobs() -> int:
    """The number of cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


# --- running the work ----------------------------------------------------------------------


def _run_packed(task: tuple) -> tuple:
    """Run ``work(item)`` and pack the outcome so that it crosses a process boundary.

    ``P3DError`` cannot be pickled as such (its constructor takes three arguments), so
    errors travel as ``("error", module, class name, where, what, hint, exit code)``.
    """
    work, item = task
    if item is None:  # standard input: done by the parent, at its turn
        return ("skip",)
    try:
        return ("ok", work(item))
    except P3DError as exc:
        return ("error", type(exc).__module__, type(exc).__qualname__, exc.where, exc.what, exc.hint,
                exc.exit_code)
    except Exception as exc:  # noqa: BLE001 - a bug on one input must not end a batch of 10,000
        if os.environ.get("P3D_DEBUG"):
            raise
        return ("error", "p3d_cli.errors", "P3DError", item,
                f"internal error: {type(exc).__name__}: {exc}",
                "this is a bug in p3d, please report it (set P3D_DEBUG=1 to see the traceback)",
                EXIT_INTERNAL)


def _unpack(item: str, packed: tuple) -> Outcome:
    if packed[0] == "ok":
        return Outcome(item, packed[1])
    _, module, name, where, what, hint, exit_code = packed
    cls = getattr(importlib.import_module(module), name, P3DError)
    error = cls.__new__(cls)
    P3DError.__init__(error, where, what, hint)
    if error.exit_code != exit_code:
        error.exit_code = exit_code
    return Outcome(item, None, error)


def _run_one(work, item) -> tuple:
    return _run_packed((work, item))


def _died(item: str, reason: str) -> tuple:
    """The packed error of an input whose worker process died doing it."""
    return ("error", "p3d_cli.errors", "InputError", item, f"not done: {reason}",
            "if it ran out of memory, run it alone (--jobs 1) or on a machine with more memory",
            InputError.exit_code)


def _in_processes(items: list[str], work, jobs: int) -> Iterator[Outcome]:
    from p3d_cli.cli import workers  # here: a one-file run need not pay for it at start-up

    tasks = [None if item == "-" else item for item in items]
    # Chunks amortise the inter-process round trip over small files, but hold results back
    # until the whole chunk is done: keep several chunks per worker.
    chunk = max(1, min(16, len(items) // (8 * jobs)))
    if workers.fork_is_safe():
        results = workers.imap_forked(functools.partial(_run_one, work), tasks, jobs, chunk, _died)
    else:
        results = _in_pool(tasks, work, jobs, chunk)
    try:
        for item, packed in zip(items, results):
            if packed[0] == "skip":
                packed = _run_packed((work, item))
            yield _unpack(item, packed)
    finally:
        results.close()


def _ignore_sigint() -> None:
    # Ctrl-C goes to the whole process group: the parent stops the pool; workers stay quiet.
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _in_pool(tasks: list[str | None], work, jobs: int, chunk: int) -> Iterator[tuple]:
    """``multiprocessing.Pool``, where fork is unsafe (threads) or missing: workers start by
    forkserver or spawn, so ``work`` travels pickled. A worker killed by the system is not
    noticed here (``Pool.imap`` waits for it); ``p3d_cli.cli.workers`` does notice."""
    import multiprocessing

    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    pool = context.Pool(jobs, initializer=_ignore_sigint)
    try:
        yield from pool.imap(_run_packed, [(work, task) for task in tasks], chunk)
        pool.close()
        pool.join()
    finally:
        pool.terminate()


def _serial(items: list[str], work) -> Iterator[Outcome]:
    for item in items:
        yield _unpack(item, _run_packed((work, item)))


def _on_dask(items: list[str], work, address: str) -> Iterator[Outcome]:
    from concurrent.futures import CancelledError

    try:
        from dask.distributed import Client, KilledWorker
    except ImportError:
        raise MissingExtraError("--dask", "needs dask.distributed, which is not installed",
                                "pip install 'p3d-cli[dask]'") from None
    try:
        client = Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise UsageError("--dask", f"cannot connect to a Dask scheduler at {address!r} ({exc})",
                         "give the scheduler's address, e.g. tcp://host:8786") from None
    try:
        remote = [(i, item) for i, item in enumerate(items) if item != "-"]
        futures = dict(zip((i for i, _ in remote),
                           client.map(_run_packed, [(work, item) for _, item in remote], pure=False)))
        for i, item in enumerate(items):
            if i not in futures:
                packed = _run_packed((work, item))
            else:
                try:
                    packed = futures[i].result()
                except KilledWorker as exc:
                    packed = _died(item, f"every Dask worker that tried it died ({exc.allowed_failures + 1} tried)")
                except CancelledError:
                    packed = _died(item, "the Dask cluster cancelled it (a worker or the scheduler was lost)")
            yield _unpack(item, packed)
    finally:
        client.close()


def run_each(inputs: Iterable[str | InputError], work: Callable[[str], object], *,
             jobs: int | None = 1, dask: str | None = None) -> Iterator[Outcome]:
    """Apply ``work`` to each input, yielding outcomes in input order as they are ready.

    Parameters
    ----------
    inputs : iterable of str or InputError
        Paths (directories are expanded here), ``-``, or errors from ``collect_inputs``
        standing in for an input: these become error outcomes in their place.
    work : callable
        ``work(path) -> result``; picklable when ``jobs > 1`` or ``dask`` is given.
    jobs : int or None
        Worker processes; None for one per core; 1 runs everything in this process.
    dask : str, optional
        A Dask scheduler address: run there instead.
    """
    ordered = list(expand_inputs(inputs))
    paths = [x for x in ordered if isinstance(x, str)]
    if dask is not None and paths:
        results = _on_dask(paths, work, dask)
    else:
        jobs = min(default_jobs() if jobs is None else jobs, len(paths))
        results = _in_processes(paths, work, jobs) if jobs > 1 else _serial(paths, work)
    try:
        for x in ordered:
            yield Outcome(x.where, None, x) if isinstance(x, P3DError) else next(results)
    finally:
        results.close()  # stops the pool or the Dask client when the caller stops early


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

    def outcomes(self, work: Callable[[str], object]) -> Iterator[Outcome]:
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
        self.note(f"p3d: error: {outcome.error.message}")
        self.errors += 1
        self.status = max(self.status, 2, outcome.error.exit_code)

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
