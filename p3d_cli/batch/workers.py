"""Worker processes started by ``fork``, each fed chunks of inputs over its own pipe.

``p3d_cli.batch.runner`` uses this for ``--jobs N`` wherever ``fork`` is safe (POSIX, and a
parent with no other thread), rather than ``multiprocessing.Pool``, for two reasons:

- A worker killed by the operating system (the out-of-memory killer, on a huge mesh) leaves
  ``Pool.imap`` waiting forever for its task. Here the parent sees that worker's pipe close,
  reports the input it was on as failed, starts a new worker and goes on.
- ``multiprocessing.pool`` costs 15-25 ms to import and its pool ~30 ms to run at all, a
  tenth of a batch of a few hundred small meshes; a fork and two pipes cost ~2 ms a worker.

The children are forks of the parent: they already hold the work function and every module
it needs, so only the inputs (strings) and the results (pickled) cross the pipes.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import select
import signal
import sys
from collections import deque
from dataclasses import dataclass, field
from typing import BinaryIO, Callable, Generator, TypeVar

Item = TypeVar("Item")
Result = TypeVar("Result")


def fork_is_safe() -> bool:
    """True when this process may fork workers: POSIX, and no thread besides this one (a lock
    another thread holds at the fork would stay held in the child forever)."""
    import threading

    return hasattr(os, "fork") and threading.active_count() == 1


@dataclass
class _Worker:
    pid: int
    tasks: BinaryIO  # the parent writes pickled chunks
    results: BinaryIO  # the parent reads pickled lists of results
    chunk: tuple[int, list] | None = None  # (index of its first item, the items) being done


@dataclass
class _Schedule:
    """Which chunks are still to do, and the results that came back out of order."""

    todo: deque = field(default_factory=deque)  # (first index, items)
    done: dict = field(default_factory=dict)  # index -> result


def imap_forked(func: Callable[[Item], Result], items: list[Item], jobs: int, chunk: int,
                died: Callable[[Item, str], Result]) -> Generator[Result, None, None]:
    """``func(item)`` for each item, in input order, computed in ``jobs`` forked processes.

    Parameters
    ----------
    func : callable
        Must not raise: errors are results (``batch._run_packed``). Runs in a child.
    items : list
        Picklable inputs.
    jobs : int
        Worker processes (fewer if there are fewer chunks).
    chunk : int
        Inputs sent to a worker at a time: more amortise the round trip, fewer balance the
        load at the end.
    died : callable
        ``died(item, reason)``: the result of an input whose worker died while doing it alone.

    When a worker dies mid-chunk, that chunk's inputs are sent again one at a time, so the
    one that kills its worker again is the only one reported by ``died``. Closing the
    generator early (Ctrl-C, or the caller stopping) kills the workers.
    """
    schedule = _Schedule(deque((i, items[i:i + chunk]) for i in range(0, len(items), chunk)))
    workers: dict[int, _Worker] = {}  # by the file number of its result pipe
    try:
        for _ in range(min(jobs, len(schedule.todo))):
            _start(func, workers)
        for worker in list(workers.values()):
            _feed(worker, func, workers, schedule)
        for index in range(len(items)):
            while index not in schedule.done:
                _wait(func, workers, schedule, died)
            yield schedule.done.pop(index)
    finally:
        _stop(workers)


def _start(func, workers: dict[int, _Worker]) -> _Worker:
    task_read, task_write = os.pipe()
    result_read, result_write = os.pipe()
    sys.stdout.flush(), sys.stderr.flush()  # a child must not write the parent's buffered output again
    pid = os.fork()
    if pid == 0:  # the child: never returns
        status = 1
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
            for other in workers.values():  # else a sibling's pipes would never see end-of-file
                other.tasks.close()
                other.results.close()
            os.close(task_write)
            os.close(result_read)
            _serve(func, os.fdopen(task_read, "rb"), os.fdopen(result_write, "wb"))
            status = 0
        except BaseException:  # noqa: BLE001 - shown, then the parent reports the inputs
            import traceback

            traceback.print_exc()
        finally:
            os._exit(status)  # never the parent's exit handlers or buffers
    os.close(task_read)
    os.close(result_write)
    worker = _Worker(pid, os.fdopen(task_write, "wb"), os.fdopen(result_read, "rb"))
    workers[worker.results.fileno()] = worker
    return worker


def _serve(func, tasks, results) -> None:
    """The child's loop: a chunk in, its list of results out, until the parent closes the pipe."""
    while True:
        try:
            chunk = pickle.load(tasks)
        except EOFError:
            return
        pickle.dump([func(item) for item in chunk], results, protocol=pickle.HIGHEST_PROTOCOL)
        results.flush()


def _assign(worker: _Worker, schedule: _Schedule) -> bool:
    """Send ``worker`` the next chunk, if any; False if the worker turns out to be dead (killed
    while idle), with the chunk back at the head of the queue."""
    if not schedule.todo:
        worker.chunk = None
        return True
    worker.chunk = schedule.todo.popleft()
    try:
        with _no_sigpipe():
            # The child is idle, reading: the write cannot block for long even past the pipe's buffer.
            pickle.dump(worker.chunk[1], worker.tasks, protocol=pickle.HIGHEST_PROTOCOL)
            worker.tasks.flush()
    except BrokenPipeError:
        schedule.todo.appendleft(worker.chunk)
        worker.chunk = None
        return False
    return True


def _feed(worker: _Worker, func, workers: dict[int, _Worker], schedule: _Schedule) -> None:
    """``_assign``, replacing the worker (after reaping it) for as long as it is found dead."""
    while not _assign(worker, schedule):
        _bury(workers.pop(worker.results.fileno()))
        _reap(worker.pid)
        worker = _start(func, workers)


@contextlib.contextmanager
def _no_sigpipe():
    """Writing to a dead worker's pipe raises BrokenPipeError here rather than killing p3d (the
    CLI restores the default SIGPIPE action so that ``p3d ... | head`` ends quietly)."""
    previous = signal.signal(signal.SIGPIPE, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGPIPE, previous)


def _wait(func, workers: dict[int, _Worker], schedule: _Schedule, died) -> None:
    """Take one message from whichever busy worker has one; replace a worker that died."""
    busy = [fd for fd, w in workers.items() if w.chunk is not None]
    ready, _, _ = select.select(busy, [], [])
    for fd in ready:
        worker = workers[fd]
        start, chunk = worker.chunk
        try:
            results = pickle.load(worker.results)  # a whole message: the child is writing it
        except (EOFError, pickle.UnpicklingError, OSError):
            _bury(workers.pop(fd))
            reason = _death(worker.pid)  # and reaped: no zombie left
            if len(chunk) == 1:
                schedule.done[start] = died(chunk[0], reason)
            else:  # again one at a time, so that only the input that kills a worker is lost
                schedule.todo.extendleft(reversed([(start + k, [item]) for k, item in enumerate(chunk)]))
            for idle in [w for w in workers.values() if w.chunk is None]:  # the redone inputs
                _feed(idle, func, workers, schedule)
            if schedule.todo:
                _feed(_start(func, workers), func, workers, schedule)
            continue
        schedule.done.update(zip(range(start, start + len(results)), results))
        _feed(worker, func, workers, schedule)


def _bury(worker: _Worker) -> None:
    for f in (worker.tasks, worker.results):
        try:
            with _no_sigpipe():
                f.close()
        except OSError:  # the child is gone: what the buffer held is of no use
            pass


def _death(pid: int) -> str:
    """How worker ``pid`` ended, in words (it has ended: its pipe is closed)."""
    _, status = os.waitpid(pid, 0)
    if os.WIFSIGNALED(status):
        number = os.WTERMSIG(status)
        try:
            name = signal.Signals(number).name
        except ValueError:
            name = f"signal {number}"
        cause = " (out of memory?)" if number == signal.SIGKILL else ""
        return f"its worker process was killed by {name}{cause}"
    return f"its worker process exited with status {os.WEXITSTATUS(status)}"


def _stop(workers: dict[int, _Worker]) -> None:
    """End every worker: at once if one is still busy (the batch was cut short), else by
    closing its task pipe, which it reads as the end."""
    for worker in workers.values():
        if worker.chunk is not None:
            try:
                os.kill(worker.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        _bury(worker)
    for worker in workers.values():
        _reap(worker.pid)
    workers.clear()


def _reap(pid: int) -> None:
    """Wait for worker ``pid`` to end, if it has not been waited for already."""
    try:
        os.waitpid(pid, 0)
    except ChildProcessError:
        pass
