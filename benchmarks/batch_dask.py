"""Is ``--dask`` on a real local cluster close to ``--jobs N`` on 1,000 small files?

Starts a Dask cluster as separate processes on 127.0.0.1 (``dask scheduler`` and
``dask worker ... --nworkers N --nthreads 1``), writes ``--files`` binary STL icospheres of
5,120 faces (0.26 MB each, each moved and scaled differently) into a temporary directory, then
times the whole command ``p3d props DIR --json --dask tcp://127.0.0.1:PORT`` against
``p3d props DIR --json --jobs N``, alternating the runs so that drift in the machine's load hits
both alike. Both outputs must be identical, byte for byte, and hold every file once, in order.

Printed per mode: medians of the wall time, of the CPU time (user + sys: for ``--jobs`` the p3d
process and its forked workers; for ``--dask`` the p3d process plus the scheduler and worker
processes, read with psutil, which dask.distributed depends on), the ratio dask / jobs of
each alternated pair, and the load average before and after. The cluster is stopped at the
end, and the whole run is bounded (``--timeout``).

    python benchmarks/batch_dask.py [--files 1000] [--workers 2] [--runs 7] [--timeout 900]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from batch_jobs import icosphere, p3d_command, write_binary_stl  # noqa: E402
from installed import cache_bytecode  # noqa: E402


def _dask_cli() -> tuple[list[str], list[str]]:
    """``dask scheduler`` and ``dask worker``, from this Python's environment."""
    exe = shutil.which("dask", path=os.path.dirname(sys.executable)) or shutil.which("dask")
    if exe is None:
        raise SystemExit("needs the dask command: pip install 'dask[distributed]'")
    return [exe, "scheduler"], [exe, "worker"]


def start_cluster(root: str, workers: int, deadline: float) -> tuple[str, list[subprocess.Popen]]:
    """A scheduler and ``workers`` single-thread worker processes, each its own process group."""
    scheduler_cmd, worker_cmd = _dask_cli()
    info = os.path.join(root, "scheduler.json")
    log = open(os.path.join(root, "cluster.log"), "wb")
    common = dict(stdout=log, stderr=log, cwd=root, start_new_session=True)
    procs = [subprocess.Popen(scheduler_cmd + ["--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                               "--scheduler-file", info], **common)]
    while not os.path.exists(info) or not os.path.getsize(info):
        if time.monotonic() > deadline or procs[0].poll() is not None:
            raise SystemExit(f"the scheduler did not start; see {log.name}")
        time.sleep(0.1)
    time.sleep(0.2)  # the file is written whole, but give it a moment
    with open(info) as f:
        address = json.load(f)["address"]
    procs.append(subprocess.Popen(worker_cmd + [address, "--nworkers", str(workers), "--nthreads", "1",
                                                "--no-dashboard", "--memory-limit", "0"], **common))
    from dask.distributed import Client

    with Client(address, timeout="30s") as client:
        client.wait_for_workers(workers, timeout=max(1.0, deadline - time.monotonic()))
    return address, procs


def stop_cluster(procs: list[subprocess.Popen]) -> None:
    """SIGTERM each process group we started, then SIGKILL what is left after 10 s."""
    for proc in reversed(procs):  # workers first, then the scheduler
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGTERM)
    for proc in reversed(procs):
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


def cluster_cpu(procs: list[subprocess.Popen]) -> float:
    """User + sys seconds of the cluster's processes and all their descendants, so far."""
    import psutil

    total = 0.0
    for proc in procs:
        try:
            root = psutil.Process(proc.pid)
            for p in [root] + root.children(recursive=True):
                t = p.cpu_times()
                total += t.user + t.system
        except psutil.NoSuchProcess:
            pass
    return total


def time_run(cmd: list[str], procs: list[subprocess.Popen], timeout: float) -> tuple[float, float, bytes]:
    """Wall and CPU seconds of ``cmd`` (children, plus the cluster's share), and its output."""
    before, cluster_before = resource.getrusage(resource.RUSAGE_CHILDREN), cluster_cpu(procs)
    start = time.perf_counter()
    done = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout, check=False)
    wall = time.perf_counter() - start
    after, cluster_after = resource.getrusage(resource.RUSAGE_CHILDREN), cluster_cpu(procs)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} exited with {done.returncode}: {done.stderr.decode()[-2000:]}")
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime + cluster_after - cluster_before
    return wall, cpu, done.stdout


def check_output(out: bytes, paths: list[str]) -> None:
    """Every file once, in input order, with a volume."""
    records = [json.loads(line) for line in out.decode().splitlines()]
    if [r["source"] for r in records] != paths or not all(r["volume"] > 0 for r in records):
        raise SystemExit("an output is incomplete, out of order or wrong")


def main() -> None:
    cache_bytecode()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=1000)
    parser.add_argument("--subdivisions", type=int, default=4, help="icosphere subdivisions (4: 5,120 faces)")
    parser.add_argument("--workers", type=int, default=2, help="Dask worker processes, and --jobs")
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--timeout", type=float, default=900, help="seconds for the whole benchmark")
    args = parser.parse_args()
    deadline = time.monotonic() + args.timeout
    load_before = os.getloadavg()
    sphere = icosphere(args.subdivisions)
    rng = np.random.default_rng(0)
    procs: list[subprocess.Popen] = []
    with tempfile.TemporaryDirectory(prefix="p3d-bench-dask-") as root:
        folder = os.path.join(root, "meshes")
        os.mkdir(folder)
        for i in range(args.files):
            scale, shift = rng.uniform(0.5, 2.0), rng.uniform(-10, 10, size=3)
            write_binary_stl(os.path.join(folder, f"part{i:04}.stl"), sphere * scale + shift)
        paths = [os.path.join(folder, name) for name in sorted(os.listdir(folder))]
        try:
            address, procs = start_cluster(root, args.workers, deadline)
            base = p3d_command() + ["props", folder, "--json"]
            modes = {"jobs": base + ["--jobs", str(args.workers)], "dask": base + ["--dask", address]}
            wall: dict[str, list[float]] = {m: [] for m in modes}
            cpu: dict[str, list[float]] = {m: [] for m in modes}
            reference = None
            for run in range(args.runs + 1):  # the first pair warms the page cache and the workers
                for mode, cmd in modes.items():
                    w, c, out = time_run(cmd, procs, max(1.0, deadline - time.monotonic()))
                    check_output(out, paths)
                    if reference is None:
                        reference = out
                    elif out != reference:
                        raise SystemExit(f"--{mode} output differs from the first run's")
                    if run:
                        wall[mode].append(w)
                        cpu[mode].append(c)
        finally:
            stop_cluster(procs)
    load_after = os.getloadavg()
    ratios = [d / j for d, j in zip(wall["dask"], wall["jobs"])]
    print(f"p3d props: {args.files} binary STL files x {len(sphere)} faces ({(84 + 50 * len(sphere)) / 1e6:.2f} MB "
          f"each), {args.workers} worker processes, {args.runs} alternating runs; outputs identical and complete")
    print(f"  load average before {load_before[0]:.1f} / {load_before[1]:.1f}, after "
          f"{load_after[0]:.1f} / {load_after[1]:.1f} (1 / 5 min) on {os.cpu_count()} cpus")
    for mode in modes:
        print(f"  --{mode:4}: wall median {statistics.median(wall[mode]):.3f} s "
              f"(runs: {', '.join(f'{t:.2f}' for t in wall[mode])}); CPU median {statistics.median(cpu[mode]):.3f} s")
    print(f"  dask / jobs, per alternated pair: median {statistics.median(ratios):.2f}x "
          f"(pairs: {', '.join(f'{r:.2f}' for r in ratios)}); ratio of CPU medians "
          f"{statistics.median(cpu['dask']) / statistics.median(cpu['jobs']):.2f}x")


if __name__ == "__main__":
    main()
