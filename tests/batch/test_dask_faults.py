"""A Dask cluster that fails under a batch (issue 24 item 2, issue 27 item 6): a scheduler lost or
silent part way ends the batch with exit status 2 and one error line, every result that
arrived written, the summary counting what was not done, and no traceback of Dask's; a listener
that never answers is given up after the documented time."""

from __future__ import annotations

import json
import socket
import threading
import time

import pytest
from click.testing import CliRunner

from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli.batch import ClusterLost, run_each
from p3d_cli.batch import runner
from p3d_cli.cli.main import cli

distributed = pytest.importorskip("dask.distributed")


class FakeFuture:
    def __init__(self, client, fn, task):
        self.client, self.fn, self.task = client, fn, task

    def result(self, timeout=None):
        self.client.asked += 1
        if self.client.asked > self.client.lose_after:
            if self.client.silent:          # the scheduler stopped answering: no result, ever
                time.sleep(min(timeout or 0, 0.05))
                raise TimeoutError
            raise distributed.client.FutureCancelledError("k", reason="scheduler-connection-lost")
        return self.fn(self.task)


class FakeClient:
    """A client whose scheduler is lost (or falls silent) after ``lose_after`` chunk results."""

    lose_after = 1
    silent = False

    def __init__(self, *args, **kwargs):
        self.asked = 0
        self.status = "running"
        FakeClient.made = self

    def nthreads(self):
        return {"tcp://worker:1": 1}

    def submit(self, fn, task, pure, priority=0):
        return FakeFuture(self, fn, task)

    def sync(self, func, *args, callback_timeout=None, **kwargs):
        raise TimeoutError   # the ping gets no answer

    @property
    def scheduler(self):
        class Scheduler:
            identity = None
        return Scheduler()

    def close(self, timeout=None):
        pass


@pytest.fixture
def fake_cluster(monkeypatch):
    monkeypatch.setattr(distributed, "Client", FakeClient)
    monkeypatch.setattr(runner, "DASK_PING", 0.01)
    # one chunk per input, so that "lost after one chunk" means after one input
    monkeypatch.setattr(runner.chunks, "plan_chunks",
                        lambda weights, slots: [range(k, k + 1) for k in range(len(weights))])
    FakeClient.lose_after, FakeClient.silent = 1, False
    return FakeClient


@pytest.fixture
def parts(tmp_path):
    for i in range(5):
        write_binary_stl(tmp_path / f"p{i}.stl", cube_triangles() * (i + 1))
    return sorted(str(p) for p in tmp_path.glob("p*.stl"))


def test_the_library_yields_what_arrived_then_raises_cluster_lost(fake_cluster):
    results = run_each(["a", "b", "c"], str.upper, dask="tcp://scheduler:8786")
    assert next(results).result == "A"
    with pytest.raises(ClusterLost) as lost:
        next(results)
    assert lost.value.exit_code == 2 and "lost the Dask scheduler" in lost.value.message


@pytest.mark.parametrize("silent", [False, True])
def test_a_lost_or_silent_scheduler_is_exit_2_one_line_results_kept_and_counted(fake_cluster, parts, tmp_path,
                                                                                 silent):
    fake_cluster.lose_after, fake_cluster.silent = 2, silent
    summary = tmp_path / "summary.json"
    junit = tmp_path / "report.xml"
    result = CliRunner().invoke(cli, ["props", *parts, "--json", "--dask", "tcp://scheduler:8786",
                                      "--summary", f"json:{summary}", "--report", f"junit:{junit}"])
    assert result.exit_code == 2, result.output
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["source"] for r in records] == parts[:2] and all("volume" in r for r in records)
    errors = [line for line in result.stderr.splitlines() if line.startswith("p3d: error:")]
    assert len(errors) == 1 and errors[0].startswith("p3d: error: --dask: lost the Dask scheduler at "
                                                     "'tcp://scheduler:8786' part way")
    assert result.stderr.splitlines()[-1] == "p3d: 5 files: 2 ok, 3 not done"
    assert "Traceback" not in result.output
    record = json.loads(summary.read_text())
    assert (record["ok"], record["errored"], record["not_done"], record["complete"], record["exit_status"]) == \
        (2, 3, 3, False, 2)
    assert junit.read_text().count("<error ") == 3 and "not done" in junit.read_text()


def test_diff_that_loses_its_scheduler_keeps_the_baseline_and_reports_nothing_vanished(fake_cluster, parts,
                                                                                       tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    base = tmp_path / "base.ndjson"
    base.write_text(CliRunner().invoke(cli, ["props", str(tmp_path), "--json"]).stdout)
    kept = base.read_text()
    result = CliRunner().invoke(cli, ["diff", str(base), str(tmp_path), "--dask", "tcp://s:1", "--update"])
    assert result.exit_code == 2
    assert "vanished" not in result.output and base.read_text() == kept


def test_a_scheduler_that_never_answers_is_given_up_in_the_documented_time(monkeypatch):
    """A listener that accepts connections and says nothing (Dask's own timeout does not cover it)."""
    monkeypatch.setattr(runner, "DASK_TIMEOUT", 1.0)
    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(16)
    accepted = []
    stop = threading.Event()

    def accept():
        listener.settimeout(0.1)
        while not stop.is_set():
            try:
                accepted.append(listener.accept()[0])
            except OSError:
                pass

    thread = threading.Thread(target=accept, daemon=True)
    thread.start()
    try:
        start = time.monotonic()
        result = CliRunner().invoke(cli, ["props", "box:1,1,1", "sphere:1", "--dask",
                                          f"tcp://127.0.0.1:{listener.getsockname()[1]}"])
        elapsed = time.monotonic() - start
    finally:
        stop.set()
        thread.join()
        for conn in accepted:
            conn.close()
        listener.close()
    assert result.exit_code == 2, result.output
    assert result.stderr.count("\n") == 1 and "no answer from a Dask scheduler" in result.stderr
    assert elapsed < 1.0 + 1.0 + 3.0   # DASK_TIMEOUT, the thread's extra second, and the import of dask


def test_a_task_that_fails_on_the_worker_is_that_chunks_error_not_a_lost_cluster(monkeypatch):
    class Broken(FakeFuture):
        def result(self, timeout=None):
            raise ModuleNotFoundError("No module named 'p3d_cli'")

    class Client(FakeClient):
        def submit(self, fn, task, pure, priority=0):
            return Broken(self, fn, task)

    monkeypatch.setattr(distributed, "Client", Client)
    out = list(run_each(["a", "b"], str.upper, dask="tcp://scheduler:8786"))
    assert [o.error.exit_code for o in out] == [2, 2]
    assert "could not run it (ModuleNotFoundError: No module named 'p3d_cli')" in out[0].error.message

