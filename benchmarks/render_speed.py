"""Whole-process time and peak memory of ``p3d render`` on grid tori of 100k and 1M triangles.

    python benchmarks/render_speed.py [--runs 3] [--sizes 100000 1000000]

Each run is a fresh ``p3d render TORUS.stl -o out.png`` (800 x 600, iso view; and once more with
``--show defects``); the table gives the median wall time of the runs and the largest peak
resident memory (the child's ``ru_maxrss``). The meshes are written by ``torus.py`` (binary STL).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def timed(command: list[str]) -> tuple[float, float, float]:
    """Wall seconds, CPU seconds (user + sys) and peak RSS (MB) of one child process (run
    through /usr/bin/time when present, for the peak of this child alone)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    prefix = ["/usr/bin/time", "-f", "%M"] if os.path.exists("/usr/bin/time") else []
    done = subprocess.run(prefix + command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    peak = float(done.stderr.strip().splitlines()[-1]) / 1024 if prefix else after.ru_maxrss / 1024
    return wall, cpu, peak


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    args = parser.parse_args()
    print("| triangles | overlays | runs | wall s (median) | cpu s (median) | peak RSS MB |")
    print("|---:|---|---:|---:|---:|---:|")
    with tempfile.TemporaryDirectory() as folder:
        for size in args.sizes:
            u = int(round((size / 2 / 2) ** 0.5))       # 2 u (2 u) ... u x 2u grid: 4 u^2 triangles
            mesh = os.path.join(folder, f"torus{size}.stl")
            subprocess.run([sys.executable, os.path.join(HERE, "torus.py"), "stl", str(u), str(2 * u), mesh,
                            "--at", "0", "0", "0"], check=True)
            out = os.path.join(folder, "out.png")
            for show in ([], ["--show", "defects"]):
                walls, cpus, peaks = [], [], []
                for _ in range(args.runs):
                    wall, cpu, peak = timed(["p3d", "render", mesh, "-o", out, *show])
                    walls.append(wall)
                    cpus.append(cpu)
                    peaks.append(peak)
                print(f"| {4 * u * u:,} | {' '.join(show[1:]) or 'none'} | {args.runs} | "
                      f"{statistics.median(walls):.2f} | {statistics.median(cpus):.2f} | {max(peaks):.0f} |")


if __name__ == "__main__":
    main()
