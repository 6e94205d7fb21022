"""Running one piece of work over many inputs: in order, in processes or on a Dask cluster.

Every input yields exactly one ``Outcome``, in input order, as soon as it and every input
before it are done: a failing input yields an error outcome and the batch goes on.

Where the work runs:

- in this process, when there is one input or ``jobs=1`` (no start-up cost);
- in ``jobs`` worker processes on this machine, in chunks, results in order: forked
  workers (``p3d_cli.batch.workers``), or ``multiprocessing.Pool`` where fork is unsafe; the
  default is the number of cores this process may use;
- on an existing Dask cluster with ``dask=ADDRESS`` (optional extra ``dask``;
  the workers need p3d installed and must see the same paths), in chunks of files sized from
  the files' sizes (``p3d_cli.batch.chunks``), a chunk's results delivered when it is done.

Standard input is always read here, at its turn. The work function may be sent to other
processes (Dask, or a pool started by spawn), so it must be picklable: a module-level
function, or a ``functools.partial`` of one with picklable arguments. Its results and p3d's
errors are pickled back as themselves.

A bug met while working on one input (an exception that is not a ``P3DError``) becomes that
input's ``InternalError`` (exit status 3) rather than ending the batch; ``P3D_DEBUG=1``
re-raises it (in a forked worker: its traceback is shown and the input is reported as not done).
"""

from __future__ import annotations

import functools
import os
import signal
from dataclasses import dataclass
from typing import Callable, Generator, Iterable

from p3d_cli.batch import chunks
from p3d_cli.batch.inputs import expand_inputs
from p3d_cli.errors import InputError, InternalError, MissingExtraError, P3DError, UsageError, install_hint


class ClusterLost(P3DError):
    """The Dask scheduler was lost (or stopped answering) part way through a batch: the
    inputs whose results had arrived were yielded; the rest were not done. Ends the batch
    (exit status 2); ``p3d_cli.cli.reporting.Batch`` counts what was not done."""

    ends_batch = True


#: Seconds p3d waits for a Dask scheduler: to connect (and finish the handshake), and for an
#: answer to a ping when no result has come for ``DASK_PING`` seconds. A scheduler that is lost
#: or silent that long ends the batch.
DASK_TIMEOUT = 10.0
DASK_PING = 5.0


@dataclass(frozen=True)
class Outcome:
    """One input's result or its error."""

    source: str
    result: object = None
    error: P3DError | None = None


def default_jobs() -> int:
    """The number of cores this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


def _run_packed(task: tuple) -> tuple:
    """Run ``work(item)``: ``("ok", result)`` or ``("error", P3DError)``, which both cross a
    process boundary as themselves (p3d's errors pickle)."""
    work, item = task
    if item is None:  # standard input: done by the parent, at its turn
        return ("skip",)
    try:
        return ("ok", work(item))
    except P3DError as exc:
        return ("error", exc)
    except Exception as exc:  # noqa: BLE001 - a bug on one input must not end a batch of 10,000
        if os.environ.get("P3D_DEBUG"):
            raise
        return ("error", InternalError(item, f"internal error: {type(exc).__name__}: {exc}",
                                       "this is a bug in p3d, please report it (set P3D_DEBUG=1 to see "
                                       "the traceback)"))


def _unpack(item: str, packed: tuple) -> Outcome:
    if packed[0] == "ok":
        return Outcome(item, packed[1])
    return Outcome(item, None, packed[1])


def _run_one(work, item) -> tuple:
    return _run_packed((work, item))


def _died(item: str | None, reason: str) -> tuple:
    """The packed error of an input whose worker process died doing it."""
    return ("error", InputError(item or "<stdin>", f"not done: {reason}",
                                "if it ran out of memory, run it alone (one job) or on a machine with "
                                "more memory"))


def _in_processes(items: list[str], work, jobs: int) -> Generator[Outcome, None, None]:
    from p3d_cli.batch import workers  # here: a one-file run need not pay for it at start-up

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


def _in_pool(tasks: list[str | None], work, jobs: int, chunk: int) -> Generator[tuple, None, None]:
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


def _serial(items: list[str], work) -> Generator[Outcome, None, None]:
    for item in items:
        yield _unpack(item, _run_packed((work, item)))


def _on_dask(items: list[str], work, address: str) -> Generator[Outcome, None, None]:
    """The inputs on the Dask cluster at ``address``, in chunks of files
    (``p3d_cli.batch.chunks``), all submitted at once; standard input here, at its turn."""
    try:
        from dask.distributed import Client
    except ImportError:
        raise MissingExtraError("dask", "needs dask.distributed, which is not installed",
                                install_hint("dask", "'dask[distributed]>=2023.1'")) from None
    _quiet_dask_logs()
    client = _connect(Client, address)
    lost = False
    try:
        remote = [item for item in items if item != "-"]
        try:
            slots = sum(client.nthreads().values())  # worker threads now (0 if none has joined yet)
            spans = chunks.plan_chunks(chunks.file_weights(remote), slots)
            # One submit per chunk, in order: each is its own graph, so the scheduler runs them
            # first come, first served, and results come back roughly in input order.
            futures = [client.submit(chunks.run_chunk, (_run_packed, work, remote[span.start:span.stop]),
                                     pure=False) for span in spans]
        except (OSError, TimeoutError) as exc:
            raise _lost(address, exc) from None
        results = _chunk_results(client, work, [remote[span.start:span.stop] for span in spans], futures, address)
        for item in items:
            yield _unpack(item, _run_packed((work, item)) if item == "-" else next(results))
    except ClusterLost:
        lost = True
        raise
    finally:
        try:
            client.close(timeout=1 if lost else DASK_TIMEOUT)
        except Exception:  # noqa: BLE001 - a lost cluster's client may fail to close: nothing is left to save
            pass


def _quiet_dask_logs() -> None:
    """Dask's own log lines (reconnection attempts, a lost scheduler's tracebacks from its event
    loop) would interleave with p3d's output; p3d reports a lost cluster itself, in one line.
    Only loggers of the client's libraries, and only in a process that runs a ``--dask`` batch."""
    import logging

    names = ("distributed", "tornado", "asyncio")
    known = [name for name in logging.root.manager.loggerDict if name.split(".")[0] in names]
    for name in {*names, *known}:
        logger = logging.getLogger(name)
        logger.setLevel(logging.CRITICAL + 1)   # Dask's configuration sets levels on child loggers too
        for handler in logger.handlers:
            handler.setLevel(logging.CRITICAL + 1)


def _connect(Client, address: str):
    """A client of the scheduler at ``address``, or ``UsageError`` within ``DASK_TIMEOUT`` (plus
    a second): Dask's own timeout covers the TCP connection, not a listener that accepts and
    never answers, so the connection is made in a thread given that long. A thread still
    waiting is left behind (a daemon: it does not keep the process alive)."""
    import threading

    box: dict = {}

    def connect() -> None:
        try:
            box["client"] = Client(address, timeout=f"{DASK_TIMEOUT:g}s", set_as_default=False)
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread below
            box["error"] = exc

    thread = threading.Thread(target=connect, name="p3d-dask-connect", daemon=True)
    thread.start()
    thread.join(DASK_TIMEOUT + 1)
    hint = "give the scheduler's address, e.g. tcp://host:8786"
    if thread.is_alive():
        raise UsageError("dask", f"no answer from a Dask scheduler at {address!r} within {DASK_TIMEOUT:g} s "
                         "(something listens there, but does not answer as a scheduler)", hint)
    error = box.get("error")
    if isinstance(error, (OSError, TimeoutError, ValueError)):
        raise UsageError("dask", f"cannot connect to a Dask scheduler at {address!r} ({error})", hint) from None
    if error is not None:
        raise UsageError("dask", f"cannot connect to a Dask scheduler at {address!r} "
                         f"({type(error).__name__}: {error})", hint) from None
    return box["client"]


def _lost(address: str, exc: BaseException | None = None) -> ClusterLost:
    why = f" ({type(exc).__name__}{': ' + str(exc) if str(exc) else ''})" if exc is not None else ""
    return ClusterLost("dask", f"lost the Dask scheduler at {address!r} part way (no answer, or the connection "
                       f"closed){why}",
                       f"the results that arrived are written; start the scheduler again and rerun the inputs "
                       f"not done (p3d waits {DASK_TIMEOUT:g} s for a scheduler that stops answering)")


def _alive(client) -> bool:
    """Whether the scheduler answers a ping within ``DASK_TIMEOUT`` seconds."""
    if getattr(client, "status", "running") not in ("running", "connecting"):
        return False
    try:
        client.sync(client.scheduler.identity, callback_timeout=DASK_TIMEOUT)
    except Exception:  # noqa: BLE001 - a timeout, a closed connection: no answer either way
        return False
    return True


def _result(future, client, address: str):
    """``future.result()``, pinging the scheduler whenever no result has come for ``DASK_PING``
    seconds; ``ClusterLost`` when it is gone or silent."""
    import asyncio

    while True:
        try:
            return future.result(timeout=DASK_PING)
        except (TimeoutError, asyncio.TimeoutError):   # one class from Python 3.11 on
            if not _alive(client):
                raise _lost(address) from None
        except OSError as exc:   # the connection to the scheduler closed under the wait
            raise _lost(address, exc) from None


def _chunk_results(client, work, parts: list[list[str]], futures: list,
                   address: str = "") -> Generator[tuple, None, None]:
    """The packed results of each chunk in turn, as each is done. A chunk that killed its
    workers (``KilledWorker``) is done again one input at a time, ahead of the rest, so that
    only the input that kills a worker again is lost, as with forked workers. A chunk
    cancelled (the scheduler, or this client's connection to it, was lost) or a scheduler that
    stops answering ends the batch: ``ClusterLost``, after every result that arrived."""
    from concurrent.futures import CancelledError

    from dask.distributed import KilledWorker

    for k, (part, future) in enumerate(zip(parts, futures)):
        futures[k] = None  # the cluster may forget a chunk's results once they are taken
        try:
            results = _result(future, client, address)
        except KilledWorker as exc:
            if len(part) == 1:
                yield _dask_failure(part[0], exc)
                continue
        except CancelledError:  # the scheduler or this client's connection was lost
            raise _lost(address) from None
        except ClusterLost:
            raise
        except Exception as exc:  # noqa: BLE001 - the task itself failed on the worker (not p3d's work,
            # which returns its errors): p3d missing there, a result that cannot be sent back
            for item in part:
                yield _died(item, f"the Dask worker could not run it ({type(exc).__name__}: {exc})")
            continue
        else:
            yield from results
            continue
        # One at a time, ahead of the chunks still queued: a task waiting on a worker when it
        # dies counts as a suspect as well, so inputs redone side by side would be lost with
        # the culprit (Dask gives up on a task after ``allowed-failures`` such deaths).
        for item in part:
            try:
                yield _result(client.submit(_run_packed, (work, item), pure=False, priority=1), client, address)
            except KilledWorker as exc:
                yield _dask_failure(item, exc)
            except CancelledError:
                raise _lost(address) from None


def _dask_failure(item: str, exc: BaseException) -> tuple:
    """The packed error of an input that the cluster could not do."""
    from dask.distributed import KilledWorker

    if isinstance(exc, KilledWorker):
        return _died(item, f"every Dask worker that tried it died ({exc.allowed_failures + 1} tried)")
    return _died(item, "the Dask cluster cancelled it (a worker or the scheduler was lost)")


def run_each(inputs: Iterable[str | InputError], work: Callable[[str], object], *,
             jobs: int | None = 1, dask: str | None = None) -> Generator[Outcome, None, None]:
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
