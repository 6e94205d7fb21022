"""Terminal manners (issue 24 item 7): the progress bar is on stderr only, off when stderr is not a
terminal, never on a line stdout writes; -q/--quiet; P3D_JOBS and P3D_DASK as defaults."""

from __future__ import annotations

import fcntl
import json
import os
import pty
import re
import select
import struct
import subprocess
import sys
import termios

import pytest
from click.testing import CliRunner

from helpers.meshes import cube_triangles, write_binary_stl
from p3d_cli.cli.main import cli

CUBE = cube_triangles()


@pytest.fixture
def many(tmp_path):
    for i in range(12):
        write_binary_stl(tmp_path / f"p{i:02d}.stl", CUBE * (i + 1))
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])   # a warning (open mesh)
    return tmp_path


def _on_a_terminal(args, env=None) -> str:
    """Run p3d with stdout and stderr on one pseudo-terminal, as in an interactive shell."""
    main, child = pty.openpty()
    fcntl.ioctl(child, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))   # 30 rows, 100 columns
    process = subprocess.Popen([sys.executable, "-m", "p3d_cli", *args], stdout=child, stderr=child,
                               stdin=subprocess.DEVNULL, env={**os.environ, "COLUMNS": "100", **(env or {})})
    os.close(child)
    out = b""
    while True:
        ready, _, _ = select.select([main], [], [], 60)
        if not ready:
            process.kill()
            break
        try:
            chunk = os.read(main, 65536)
        except OSError:   # the child closed the terminal
            break
        if not chunk:
            break
        out += chunk
    process.wait(timeout=60)
    os.close(main)
    return out.decode("utf-8", "replace")


def test_results_never_share_a_line_with_the_progress_bar(many):
    text = _on_a_terminal(["props", str(many), "--json", "--jobs", "1"])
    starts = [m.start() for m in re.finditer(r'\{"schema_version"', text)]
    assert len(starts) == 13
    for start in starts:
        # a record begins a line: after a line end, or after the bar was cleared (carriage return)
        assert start == 0 or text[start - 1] in "\r\n", repr(text[max(0, start - 80):start + 20])
        line = text[start:].split("\n", 1)[0].rstrip("\r")
        assert json.loads(line)["volume"] > 0
    assert "file/s]" in text and "%|" in text   # the bar was there on the terminal


def test_no_bar_when_stderr_is_not_a_terminal(many):
    done = subprocess.run([sys.executable, "-m", "p3d_cli", "props", str(many), "--json", "--jobs", "1"],
                          capture_output=True, text=True, timeout=120)
    assert "\r" not in done.stderr and "%|" not in done.stderr


def test_quiet_leaves_only_results_and_errors(many):
    result = CliRunner().invoke(cli, ["props", str(many), "--json", "-q", "--jobs", "1"])
    assert result.exit_code == 0 and result.stderr == ""
    assert len(result.stdout.splitlines()) == 13
    (many / "bad.stl").write_bytes(b"\0" * 90)
    result = CliRunner().invoke(cli, ["check", str(many), "--quiet"])
    assert result.exit_code == 2
    assert [line.split(":")[1] for line in result.stderr.splitlines()] == [" error"]


def test_environment_defaults_for_jobs_and_dask(many):
    done = CliRunner().invoke(cli, ["props", "--help"])
    text = " ".join(done.stdout.split())
    assert "env var: P3D_JOBS" in text and "env var: P3D_DASK" in text
    bad = CliRunner().invoke(cli, ["props", str(many), "--json"], env={"P3D_JOBS": "0"})
    assert bad.exit_code == 2 and "P3D_JOBS" in bad.stderr
    # The command line wins over the other option's environment default (no "both given").
    local = CliRunner().invoke(cli, ["props", str(many / "p00.stl"), str(many / "p01.stl"), "--jobs", "1"],
                               env={"P3D_DASK": "tcp://127.0.0.1:1"})
    assert local.exit_code == 0, local.output
    both = CliRunner().invoke(cli, ["props", str(many), "--jobs", "1", "--dask", "tcp://127.0.0.1:1"])
    assert both.exit_code == 2 and "both given" in both.stderr


def test_p3d_jobs_sets_the_worker_count(many, monkeypatch):
    from p3d_cli.cli import reporting

    seen = []
    real = reporting.run_each

    def spy(items, work, *, jobs=1, dask=None):
        seen.append(jobs)
        return real(items, work, jobs=jobs, dask=dask)

    monkeypatch.setattr(reporting, "run_each", spy)
    assert CliRunner().invoke(cli, ["check", str(many)], env={"P3D_JOBS": "1"}).exit_code == 1
    assert seen == [1]
