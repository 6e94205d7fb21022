"""Before/after: whole-process timings of two source trees of p3d on the same files, side by side.

Usage::

    git worktree add /tmp/p3d-before <commit>
    python benchmarks/revisions.py --baseline /tmp/p3d-before [--runs 15]

Each case runs ``p3d ...`` from one tree, then the other (through ``tree.py``, which checks
that the p3d_cli imported is the tree's),
alternating, so both see the same machine load. Reported: median wall and CPU (user + system)
seconds of each tree, and the ratio after/before; and the machine's load average. Cases: start-up
on a tiny STL (``props --json``), ``p3d --help``, and 1M-triangle binary STL props (closed).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from installed import cache_bytecode

HERE = Path(__file__).resolve().parent.parent


def write_binary_stl(path: Path, triangles: np.ndarray) -> None:
    records = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = triangles
    with open(path, "wb") as f:
        f.write(b"p3d benchmark".ljust(80, b" ") + struct.pack("<I", len(triangles)))
        f.write(records.tobytes())


def torus(n: int) -> np.ndarray:
    """A closed torus of about ``n`` triangles."""
    k = max(3, int(round((n / 2) ** 0.5)))
    u, v = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")

    def point(i, j):
        a, b = 2 * np.pi * i / k, 2 * np.pi * j / k
        return np.stack([(3 + np.cos(b)) * np.cos(a), (3 + np.cos(b)) * np.sin(a), np.sin(b)], axis=-1)

    # Indices wrap (k -> 0), so the seam's vertices are bit-identical and the torus is closed.
    p00, p10 = point(u, v), point((u + 1) % k, v)
    p01, p11 = point(u, (v + 1) % k), point((u + 1) % k, (v + 1) % k)
    quads = np.stack([p00, p10, p11, p01], axis=2).reshape(-1, 4, 3)
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def timed(tree: Path, args: list[str]) -> tuple[float, float]:
    # Through tree.py: ``PYTHONPATH=TREE python -m p3d_cli`` runs the working folder's or an
    # editable install's p3d_cli, not TREE's, and both sides would time the same code.
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([sys.executable, str(HERE / "benchmarks" / "tree.py"), str(tree), *args], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    cache_bytecode()
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, type=Path, help="source tree of the 'before' revision")
    parser.add_argument("--runs", type=int, default=15, help="runs per tree and case (default 15)")
    parser.add_argument("--large-runs", type=int, default=7, help="runs at 1M triangles (default 7)")
    options = parser.parse_args()
    work = Path(tempfile.mkdtemp(prefix="p3d-revisions-"))
    tiny = work / "tiny.stl"
    write_binary_stl(tiny, torus(200))
    large = work / "large.stl"
    write_binary_stl(large, torus(1_000_000))
    cases = [("props tiny.stl --json", ["props", str(tiny), "--json"], options.runs),
             ("--help", ["--help"], options.runs),
             ("props 1M binary STL", ["props", str(large)], options.large_runs)]
    trees = {"before": options.baseline.resolve(), "after": HERE}
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    print("| case | before wall | after wall | ratio | before CPU | after CPU | ratio |")
    print("|---|---|---|---|---|---|---|")
    for name, args, runs in cases:
        for tree in trees.values():
            timed(tree, args)  # warm the page cache and the bytecode
        got: dict[str, list[tuple[float, float]]] = {k: [] for k in trees}
        for _ in range(runs):
            for key, tree in trees.items():
                got[key].append(timed(tree, args))
        med = {k: (statistics.median(w for w, _ in v), statistics.median(c for _, c in v)) for k, v in got.items()}
        (bw, bc), (aw, ac) = med["before"], med["after"]
        print(f"| {name} | {bw:.3f} s | {aw:.3f} s | {aw / bw:.2f} | {bc:.3f} s | {ac:.3f} s | {ac / bc:.2f} |")
    print(f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
