"""Forked workers: results in order and once, and a worker killed mid-batch loses one input only."""

from __future__ import annotations

import os
import pickle
import signal
import subprocess
import sys
import textwrap
import threading
from collections import deque

import pytest

from p3d_cli.batch import runner as batch
from p3d_cli.batch import workers
from p3d_cli.batch import run_each

# imap_forked forks whatever threads this process has (earlier tests may leave some behind);
# the work here takes no lock, so that is safe. The batch decides with fork_is_safe().
pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="needs fork")


def died(item, reason):
    return ("died", item, reason)


def square(n):
    return n * n


def kill_on_7(n):
    if n == 7:
        os.kill(os.getpid(), signal.SIGKILL)
    return n * n


def exit_on_3(n):
    if n == 3:
        os._exit(5)
    return n * n


@pytest.mark.parametrize("jobs,chunk", [(1, 1), (2, 1), (2, 4), (3, 5), (4, 100)])
def test_results_in_order_once(jobs, chunk):
    assert list(workers.imap_forked(square, list(range(23)), jobs, chunk, died)) == [n * n for n in range(23)]
    assert list(workers.imap_forked(square, [], jobs, chunk, died)) == []


@pytest.mark.parametrize("chunk", [1, 4])
def test_a_killed_worker_loses_only_its_input(chunk):
    out = list(workers.imap_forked(kill_on_7, list(range(20)), 2, chunk, died))
    assert out[:7] == [n * n for n in range(7)] and out[8:] == [n * n for n in range(8, 20)]
    assert out[7] == ("died", 7, "its worker process was killed by SIGKILL (out of memory?)")


def test_a_worker_that_exits_is_reported_with_its_status():
    out = list(workers.imap_forked(exit_on_3, list(range(6)), 2, 2, died))
    assert out[3] == ("died", 3, "its worker process exited with status 5")
    assert [x for k, x in enumerate(out) if k != 3] == [0, 1, 4, 16, 25]


def pid_of_worker(_):
    return os.getpid()


def test_stopping_early_ends_every_worker():
    results = workers.imap_forked(pid_of_worker, list(range(1000)), 2, 1, died)
    pids = {next(results) for _ in range(50)}
    assert len(pids) == 2 and os.getpid() not in pids
    results.close()
    for pid in pids:  # gone and reaped: not even a zombie is left
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)


def test_a_worker_killed_while_idle_does_not_take_p3d_with_it():
    pool = {}
    worker = workers._start(square, pool)
    os.kill(worker.pid, signal.SIGKILL)
    os.waitid(os.P_PID, worker.pid, os.WEXITED | os.WNOWAIT)  # dead, not yet reaped
    schedule = workers._Schedule(deque([(0, [1, 2]), (2, [3])]))
    previous = signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # as in the CLI: writing would kill
    try:
        workers._feed(worker, square, pool, schedule)
    finally:
        signal.signal(signal.SIGPIPE, previous)
    assert list(schedule.todo) == [(2, [3])] and worker not in pool.values()
    (replacement,) = pool.values()
    assert replacement.chunk == (0, [1, 2]) and replacement.pid != worker.pid
    assert pickle.load(replacement.results) == [1, 4]
    workers._stop(pool)


def test_the_batch_reports_a_killed_worker_as_an_input_error():
    # In a fresh interpreter: with no other thread there, the batch forks its own workers.
    code = textwrap.dedent("""
        import os, signal
        from p3d_cli.batch import workers
        from p3d_cli.batch import run_each

        def work(text):
            if text == "7":
                os.kill(os.getpid(), signal.SIGKILL)
            return int(text) ** 2

        assert workers.fork_is_safe()
        for o in run_each([str(n) for n in range(10)], work, jobs=2):
            print(o.source, o.result, o.error and o.error.exit_code, o.error and o.error.message, sep="|")
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    rows = [line.split("|") for line in done.stdout.splitlines()]
    assert [r[0] for r in rows] == [str(n) for n in range(10)]
    assert [r[1] for r in rows if r[0] != "7"] == [str(n * n) for n in range(10) if n != 7]
    assert rows[7][1:3] == ["None", "2"]
    assert rows[7][3].startswith("7: not done: its worker process was killed by SIGKILL (out of memory?); ")


def test_fork_is_unsafe_while_another_thread_runs():
    stop = threading.Event()
    thread = threading.Thread(target=stop.wait)
    thread.start()
    try:
        assert not workers.fork_is_safe()
    finally:
        stop.set()
        thread.join()


def test_without_fork_the_pool_gives_the_same_results(monkeypatch):
    monkeypatch.setattr(workers, "fork_is_safe", lambda: False)
    calls = []
    real = batch._in_pool
    monkeypatch.setattr(batch, "_in_pool", lambda *args: calls.append(1) or real(*args))
    out = list(run_each([str(n) for n in range(10)], batch_square, jobs=2))
    assert calls and [o.result for o in out] == [n * n for n in range(10)]


def batch_square(text):
    return int(text) ** 2
