"""Time p3d as it runs installed: with its bytecode cached.

An installed package has its modules compiled once (pip writes the ``.pyc`` files, or the first
run does). A development shell that sets ``PYTHONDONTWRITEBYTECODE=1`` would instead make an
editable p3d compile every module from source on every run, while numpy, trimesh and dask
load their cached bytecode: 0.1-0.2 s of every p3d process that no user pays. Every benchmark
that starts processes calls ``cache_bytecode()`` first; the cache goes to a folder of its own
(``PYTHONPYCACHEPREFIX``), so the source tree is left as it is. ``run_once`` times one such
process.
"""

from __future__ import annotations

import os
import tempfile


def cache_bytecode(folder: str | None = None) -> dict:
    """Let this process's children write and read cached bytecode (in ``folder``, default a
    folder under the temporary directory), and return the environment they get."""
    os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
    os.environ["PYTHONPYCACHEPREFIX"] = folder or os.path.join(tempfile.gettempdir(), "p3d-bench-pycache")
    return dict(os.environ)


def run_once(argv, env) -> tuple[float, float, float, int, str]:
    """Run ``argv`` as a whole process; return wall s, user+sys s, peak RSS MB, exit status
    and stdout (CPU time and peak memory from ``os.wait4``, as ``/usr/bin/time -v`` shows them)."""
    import subprocess
    import sys
    import time

    with tempfile.TemporaryFile() as out:
        start = time.perf_counter()
        child = subprocess.Popen(argv, stdout=out, stderr=subprocess.DEVNULL,
                                 stdin=subprocess.DEVNULL, env=env)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        out.seek(0)
        text = out.read().decode(errors="replace")
    rss = usage.ru_maxrss / (1 << 20 if sys.platform == "darwin" else 1 << 10)
    return wall, usage.ru_utime + usage.ru_stime, rss, os.waitstatus_to_exitcode(status), text


def alternated(tools: dict, runs: int, env) -> dict:
    """Time every tool ``runs`` times as whole processes, after one untimed warm-up run that
    also checks its answer, run ``r`` of every tool before run ``r + 1`` of any and the order
    rotated run by run (slow drifts of the machine hit all tools alike).

    ``tools``: name -> ``(argv, ok)``, ``ok(status, stdout)`` saying whether the answer is
    right. Returns name -> ``{"wall": [...], "cpu": [...], "rss": [...], "stdout": [...]}``.
    """
    results = {name: {"wall": [], "cpu": [], "rss": [], "stdout": []} for name in tools}
    names = list(tools)
    for name in names:
        argv, ok = tools[name]
        *_, status, text = run_once(argv, env)
        if not ok(status, text):
            raise SystemExit(f"{name}: unexpected answer (exit {status}): {text[:300]}")
    for r in range(runs):
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            wall, cpu, rss, _, text = run_once(tools[name][0], env)
            for key, value in (("wall", wall), ("cpu", cpu), ("rss", rss), ("stdout", text)):
                results[name][key].append(value)
    return results
