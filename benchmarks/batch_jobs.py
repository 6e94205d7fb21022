"""Does ``--jobs 2`` beat ``--jobs 1`` on a directory of a few hundred small meshes?

Writes N binary STL spheres (icospheres of 5,120 and 20,480 faces by default: 0.26 and 1.0 MB,
each moved and scaled differently) into a temporary directory per size, then times the whole command ``p3d props DIR --json --jobs J``
(process start-up included, output to /dev/null) for J = 1 and 2, alternating the runs so
that drift in the machine's load hits both alike, and prints the medians and their ratio.

For scale it also times the best any two-process scheme could do here: two independent
``--jobs 1`` processes started together, each on half of the files (both start-ups
included, no coordination). ``--jobs 2`` cannot beat that; how close it comes is the
batch machinery's efficiency. Neither removes the ~0.1 s of one process start-up, which is why
the smaller the files, the smaller the speed-up of a whole run.

    python benchmarks/batch_jobs.py [--files 300] [--subdivisions 4 5] [--runs 7] [--command check]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
from installed import cache_bytecode


def icosphere(subdivisions: int) -> np.ndarray:
    """A unit icosphere as (n, 3, 3) float64 outward-wound triangles (n = 20 * 4**subdivisions)."""
    t = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
                  [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
                  [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]])
    tri = v[f] / np.linalg.norm(v[f], axis=2, keepdims=True)
    for _ in range(subdivisions):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = ((p + q) / 2 for p, q in ((a, b), (b, c), (c, a)))
        ab, bc, ca = (m / np.linalg.norm(m, axis=1, keepdims=True) for m in (ab, bc, ca))
        tri = np.concatenate([np.stack(x, axis=1) for x in
                              ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])
    return tri


def write_binary_stl(path: str, triangles: np.ndarray) -> None:
    records = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = triangles
    with open(path, "wb") as f:
        f.write(b"p3d benchmark".ljust(80))
        f.write(np.uint32(len(triangles)).tobytes())
        f.write(records.tobytes())


def p3d_command() -> list[str]:
    exe = shutil.which("p3d", path=os.path.dirname(sys.executable)) or shutil.which("p3d")
    return [exe] if exe else [sys.executable, "-m", "p3d_cli"]


CPU: dict[int, list[float]] = {1: [], 2: []}


def time_halves(cmds: list[list[str]]) -> float:
    """Wall time of ``cmds`` started together, until the last one ends."""
    start = time.perf_counter()
    running = [subprocess.Popen(c, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL) for c in cmds]
    for process in running:
        process.wait()
    return time.perf_counter() - start


def time_run(cmd: list[str], jobs: int | None = None) -> float:
    """Wall time of ``cmd``; its CPU time (workers included) goes to ``CPU[jobs]``."""
    import resource

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if jobs is not None:
        CPU[jobs].append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return wall


def _spin(n: int) -> int:
    total = 0
    for i in range(n):
        total += i
    return total


def machine_speedup(tasks: int = 16, n: int = 1_000_000) -> float:
    """What two processes gain over one on a pure-CPU task on this machine, right now.

    On a shared or busy machine this is well below 2, and no ``--jobs`` can do better:
    printed so that a small speed-up of p3d can be told from a machine without a free core.
    """
    import multiprocessing

    start = time.perf_counter()
    for _ in range(tasks):
        _spin(n)
    serial = time.perf_counter() - start
    with multiprocessing.get_context("fork").Pool(2) as pool:
        start = time.perf_counter()
        pool.map(_spin, [n] * tasks)
        parallel = time.perf_counter() - start
    return serial / parallel


def bench(command: str, files: int, subdivisions: int, runs: int) -> None:
    """Time one directory of ``files`` spheres of ``20 * 4**subdivisions`` faces; print a summary."""
    sphere = icosphere(subdivisions)
    rng = np.random.default_rng(0)
    CPU[1].clear(), CPU[2].clear()
    with tempfile.TemporaryDirectory(prefix="p3d-bench-") as root:
        folder = os.path.join(root, "meshes")
        os.mkdir(folder)
        for i in range(files):
            scale, shift = rng.uniform(0.5, 2.0), rng.uniform(-10, 10, size=3)
            write_binary_stl(os.path.join(folder, f"part{i:04}.stl"), sphere * scale + shift)
        base = p3d_command() + [command, folder, "--json"]
        names = sorted(os.listdir(folder))
        halves = []
        for k, part in enumerate((names[:len(names) // 2], names[len(names) // 2:])):
            listing = os.path.join(root, f"half{k}.txt")
            with open(listing, "w") as f:
                f.write("".join(os.path.join(folder, name) + "\n" for name in part))
            halves.append(p3d_command() + [command, "--files-from", listing, "--json", "--jobs", "1"])
        times: dict[int, list[float]] = {1: [], 2: []}
        ideal: list[float] = []
        time_run(base + ["--jobs", "1"])  # warm the page cache and the imports
        for _ in range(runs):
            for jobs in (1, 2):
                times[jobs].append(time_run(base + ["--jobs", str(jobs)], jobs))
            ideal.append(time_halves(halves))
    one, two, best = statistics.median(times[1]), statistics.median(times[2]), statistics.median(ideal)
    size = 84 + 50 * len(sphere)  # binary STL: header, count, 50 bytes a triangle
    print(f"p3d {command}: {files} binary STL files x {len(sphere)} faces ({size / 1e6:.2f} MB each), "
          f"{runs} alternating runs")
    print(f"  --jobs 1: median {one:.3f} s  (runs: {', '.join(f'{t:.3f}' for t in times[1])})")
    print(f"  --jobs 2: median {two:.3f} s  (runs: {', '.join(f'{t:.3f}' for t in times[2])})")
    print(f"  speed-up --jobs 2 / --jobs 1: {one / two:.2f}x")
    print(f"  ceiling: two independent --jobs 1 processes on the halves, together: median {best:.3f} s "
          f"({one / best:.2f}x); --jobs 2 gets {(one - two) / (one - best):.0%} of that gain")
    print(f"  CPU time (user + sys, workers included), median: --jobs 1 "
          f"{statistics.median(CPU[1]):.3f} s, --jobs 2 {statistics.median(CPU[2]):.3f} s")


def main() -> None:
    cache_bytecode()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--files", type=int, default=300)
    parser.add_argument("--subdivisions", type=int, nargs="+", default=[4, 5],
                        help="icosphere subdivisions, one directory each (4: 5,120 faces; 5: 20,480)")
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--command", default="props", choices=["props", "check"])
    args = parser.parse_args()

    print(f"{os.cpu_count()} cpus; this machine's own two-process speed-up on pure CPU work, now: "
          f"{machine_speedup():.2f}x; load average {os.getloadavg()[0]:.1f}")
    for subdivisions in args.subdivisions:
        bench(args.command, args.files, subdivisions, args.runs)


if __name__ == "__main__":
    main()
