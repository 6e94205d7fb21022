"""Batches: every good result arrives once, in order, in serial, with --jobs 2 and on Dask."""

from __future__ import annotations

import csv
import functools
import io
import json
import os
import signal
import subprocess
import sys
import time

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli.cli import reporting as batch_module
from p3d_cli.batch import run_each
from p3d_cli.measure import check as check_file
from p3d_cli.errors import InputError

CUBE = cube_triangles()


@pytest.fixture
def mixed(tmp_path):
    """A directory of good, failing and corrupt meshes, and the expected verdicts in order.

    Returns (directory, list file naming the directory's files plus a missing one, expected),
    where ``expected`` maps each source to "ok", "failed" or "error".
    """
    folder = tmp_path / "meshes"
    (folder / "sub").mkdir(parents=True)
    expected = {}
    for i in range(7):
        path = folder / f"good{i}.stl"
        write_binary_stl(path, CUBE * (i + 1))
        expected[str(path)] = "ok"
    corrupt = folder / "sub" / "corrupt.stl"
    corrupt.write_bytes(b"\x00" * 80 + (1000).to_bytes(4, "little") + b"\x00" * 60)
    expected[str(corrupt)] = "error"
    open_mesh = folder / "sub" / "open.stl"
    write_binary_stl(open_mesh, CUBE[2:])
    expected[str(open_mesh)] = "failed"
    (folder / "notes.txt").write_text("not a mesh, not searched")
    missing = str(tmp_path / "missing.stl")
    listing = tmp_path / "list.txt"
    listing.write_text("\n".join(list(expected) + ["", missing]) + "\n")
    expected[missing] = "error"
    return folder, listing, expected


def verdicts(stdout: str) -> list[tuple[str, str]]:
    out = []
    for line in stdout.splitlines():
        r = json.loads(line)
        out.append((r["source"], "error" if "error" in r else "ok" if r["ok"] else "failed"))
    return out


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_files_from_mixed_batch_in_order_once(mixed, jobs):
    _, listing, expected = mixed
    result = run("check", "--files-from", listing, "--json", "--jobs", jobs)
    assert verdicts(result.stdout) == list(expected.items())
    assert result.exit_code == 2  # something could not be read; failures alone would give 1
    assert result.stderr.rstrip().splitlines()[-1] == "p3d: 10 files: 7 ok, 1 failed check, 2 errors"
    assert result.stderr.count("p3d: error: ") == 2


def test_directory_is_searched_sorted_and_recursively(mixed):
    folder, _, expected = mixed
    result = run("check", folder, "--json", "-j", "2")
    in_folder = [(s, v) for s, v in expected.items() if s.startswith(str(folder))]
    assert verdicts(result.stdout) == in_folder
    assert "notes.txt" not in result.stdout


def test_failures_without_errors_exit_1(mixed):
    folder, _, _ = mixed
    (folder / "sub" / "corrupt.stl").unlink()
    result = run("check", folder)
    assert result.exit_code == 1 and "1 failed check" in result.stderr


def test_files_from_standard_input_and_arguments_together(mixed, tmp_path):
    folder, _, _ = mixed
    extra = tmp_path / "extra.stl"
    write_binary_stl(extra, CUBE)
    paths = f"{folder / 'good1.stl'}\n\n  {folder / 'good0.stl'}  \n"
    result = run("check", extra, "--files-from", "-", "--json", input=paths)
    assert [s for s, _ in verdicts(result.stdout)] == [str(extra), str(folder / "good1.stl"),
                                                       str(folder / "good0.stl")]
    assert result.exit_code == 0


def test_files_from_errors(tmp_path):
    result = run("check", "--files-from", tmp_path / "none.txt")
    assert result.exit_code == 2 and f"p3d: error: {tmp_path / 'none.txt'}: no such file" in result.stderr
    empty = tmp_path / "empty.txt"
    empty.write_text("\n\n")
    result = run("check", "--files-from", empty)
    assert result.exit_code == 2 and "lists no files" in result.stderr
    result = run("check", "-", "--files-from", "-", input="x\n")
    assert result.exit_code == 2 and "standard input cannot hold both" in result.stderr


def test_empty_directory_is_an_error_record(tmp_path):
    (tmp_path / "empty").mkdir()
    result = run("check", tmp_path / "empty", "--json")
    assert result.exit_code == 2
    assert json.loads(result.stdout)["error"].endswith("directory holds no mesh files; p3d reads .stl, "
                                                       ".obj, .ply, .off and meshio's formats")


def test_props_batch_csv_with_jobs(mixed):
    folder, _, expected = mixed
    result = run("props", folder, "--csv", "--jobs", "2")
    assert result.exit_code == 2
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    in_folder = [s for s in expected if s.startswith(str(folder))]
    assert [r["source"] for r in rows] == in_folder
    assert rows[0]["volume"] == "1.0" and rows[0]["ixx"] and rows[0]["error"] == ""
    corrupt = next(r for r in rows if r["source"].endswith("corrupt.stl"))
    assert corrupt["error"] and corrupt["volume"] == ""
    assert "p3d: 9 files: 8 ok, 1 error" in result.stderr


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_warnings_and_strict_verdicts_cross_from_workers(tmp_path, jobs):
    for i in range(3):
        write_binary_stl(tmp_path / f"good{i}.stl", CUBE * (i + 1))
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    result = run("props", tmp_path, "--json", "--strict", "--jobs", jobs)
    assert result.exit_code == 1
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [os.path.basename(r["source"]) for r in records] == ["good0.stl", "good1.stl", "good2.stl", "open.stl"]
    assert [r["volume"] for r in records[:3]] == [1.0, 8.0, 27.0] and records[3]["warnings"]
    assert result.stderr.count("p3d: warning: ") == len(records[3]["warnings"])
    assert "p3d: 4 files: 3 ok, 1 with warnings (--strict)" in result.stderr
    assert "p3d: error: --strict: some result carries a warning" in result.stderr


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_unknown_field_ends_the_batch_as_a_usage_error(mixed, jobs):
    folder, _, _ = mixed
    result = run("props", folder, "--field", "volumen", "--jobs", jobs)
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr.count("no field named 'volumen'") == 1 and "fields are: source," in result.stderr
    assert "files:" not in result.stderr  # no summary: the command line was wrong, not a file


def test_jobs_and_dask_together_is_a_usage_error(tmp_path):
    result = run("check", tmp_path, "--jobs", "2", "--dask", "tcp://127.0.0.1:1")
    assert result.exit_code == 2 and "--jobs/--dask: both given" in result.stderr
    assert run("check", tmp_path, "--jobs", "0").exit_code == 2


def test_missing_dask_names_the_extra(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)  # import fails
    path = tmp_path / "a.stl"
    write_binary_stl(path, CUBE)
    result = run("check", path, path, "--dask", "tcp://127.0.0.1:1")
    assert result.exit_code == 2
    assert "p3d: error: --dask: needs dask.distributed, which is not installed; install p3d's extra 'dask': " \
        "pip install 'dask[distributed]>=2023.1'" in result.stderr


# --- the machinery ------------------------------------------------------------------------------


def pid_of_worker(path):
    return os.getpid()


def broken(path):
    if path.endswith("bad"):
        raise ZeroDivisionError("division by zero")
    return path


def test_jobs_run_in_other_processes_and_serial_in_this_one():
    items = [f"x{i}" for i in range(8)]
    pids = {o.result for o in run_each(items, pid_of_worker, jobs=2)}
    assert os.getpid() not in pids and 1 <= len(pids) <= 2
    assert {o.result for o in run_each(items, pid_of_worker, jobs=1)} == {os.getpid()}
    assert {o.result for o in run_each(items[:1], pid_of_worker, jobs=None)} == {os.getpid()}


@pytest.mark.parametrize("jobs", [1, 2])
def test_a_bug_on_one_input_is_an_error_record_with_status_3(jobs):
    out = list(run_each(["a", "bad", "c"], broken, jobs=jobs))
    assert [o.source for o in out] == ["a", "bad", "c"]
    assert out[0].result == "a" and out[2].result == "c"
    assert out[1].error.exit_code == 3
    assert out[1].error.message.startswith("bad: internal error: ZeroDivisionError: division by zero; "
                                           "this is a bug in p3d")


def test_debug_reraises_bugs(monkeypatch):
    monkeypatch.setenv("P3D_DEBUG", "1")
    with pytest.raises(ZeroDivisionError):
        list(run_each(["bad"], broken))


def test_errors_cross_the_process_boundary_as_themselves(tmp_path):
    work = functools.partial(check_file, format=None, require=(), min_volume=None, max_faces=None)
    missing = str(tmp_path / "missing.stl")
    out = list(run_each([missing, missing], work, jobs=2))
    for o in out:
        assert isinstance(o.error, InputError) and o.error.exit_code == 2
        assert (o.error.where, o.error.what) == (missing, "no such file")


def test_progress_bar_only_on_a_terminal_and_for_big_batches(monkeypatch):
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Terminal())
    bar = batch_module._progress_bar(10)
    assert bar is not None
    bar.close()
    assert batch_module._progress_bar(batch_module.PROGRESS_ABOVE) is None
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert batch_module._progress_bar(1000) is None


def test_ctrl_c_keeps_written_lines_and_exits_130(tmp_path):
    for i in range(300):
        write_binary_stl(tmp_path / f"m{i:03}.stl", CUBE + i)
    # Unbuffered: communicate() reads the pipe directly, past anything a buffer held back.
    # The last input is standard input, read by p3d at its turn and never written here: the
    # batch cannot end before the Ctrl-C, however fast the files go (on a loaded machine the
    # 300 files could all be done before the signal landed).
    proc = subprocess.Popen([sys.executable, "-m", "p3d_cli", "props", str(tmp_path), "-", "--format", "stl",
                             "--json", "--jobs", "2"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True, bufsize=0)
    first = proc.stdout.readline()
    os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole process group
    rest, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, err
    lines = (first + rest).decode().splitlines()
    assert lines and all(json.loads(line)["source"] for line in lines)  # every line whole
    assert [json.loads(line)["source"] for line in lines] == \
        [str(tmp_path / f"m{i:03}.stl") for i in range(len(lines))]
    assert b"Traceback" not in err


# --- a local Dask cluster ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def dask_address():
    if os.environ.get("CI") != "true":
        pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=":0") as cluster:
        yield cluster.scheduler_address
    time.sleep(0.1)


def test_dask_mixed_batch_in_order_once(mixed, dask_address):
    _, listing, expected = mixed
    result = run("check", "--files-from", listing, "--json", "--dask", dask_address)
    assert verdicts(result.stdout) == list(expected.items())
    assert result.exit_code == 2
    assert "p3d: 10 files: 7 ok, 1 failed check, 2 errors" in result.stderr


def test_dask_props_with_standard_input_done_locally(mixed, dask_address):
    folder, _, _ = mixed
    good = folder / "good2.stl"
    result = run("props", good, "-", "--format", "stl", "--json", "--dask", dask_address,
                 input=good.read_bytes())
    assert result.exit_code == 0, result.stderr
    records = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["source"] for r in records] == [str(good), "-"]
    assert records[0]["volume"] == records[1]["volume"] == 27.0


def test_the_program_after_a_dask_batch_ends_with_its_status_and_all_its_output(mixed):
    # ``python -m p3d_cli`` (the console script's ``run``) skips dask.distributed's teardown
    # with os._exit: every line must still be written, in order, and the status kept. The
    # cluster listens on TCP, so that another process can reach it.
    if os.environ.get("CI") != "true":
        pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    _, listing, expected = mixed
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False, protocol="tcp",
                      dashboard_address=":0") as cluster:
        done = subprocess.run([sys.executable, "-m", "p3d_cli", "check", "--files-from", str(listing), "--json",
                               "--dask", cluster.scheduler_address], capture_output=True, text=True, timeout=120)
    assert verdicts(done.stdout) == list(expected.items())
    assert done.returncode == 2
    assert done.stderr.rstrip().endswith("p3d: 10 files: 7 ok, 1 failed check, 2 errors")
    assert "Traceback" not in done.stderr


def test_dask_losing_a_task_is_that_input_error(monkeypatch):
    distributed = pytest.importorskip("dask.distributed")

    class Future:
        def __init__(self, fn, task):
            self.fn, self.task = fn, task

        def result(self, timeout=None):
            if "b" in self.task[-1]:  # a chunk holding "b", or "b" alone: every worker that tried it died
                raise distributed.KilledWorker("run-b", None, 3)
            return self.fn(self.task)

    class Client:
        def __init__(self, *args, **kwargs):
            pass

        def nthreads(self):
            return {"tcp://worker:1": 2}

        def submit(self, fn, task, pure, priority=0):
            return Future(fn, task)

        def close(self):
            pass

    monkeypatch.setattr(distributed, "Client", Client)
    out = list(run_each(["a", "b", "c"], str.upper, dask="tcp://scheduler:8786"))
    assert [o.result for o in out] == ["A", None, "C"]
    assert out[1].error.exit_code == 2
    assert out[1].error.message.startswith("b: not done: every Dask worker that tried it died (4 tried); ")
