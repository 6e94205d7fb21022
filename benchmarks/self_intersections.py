#!/usr/bin/env python
"""Whole-process timings of ``p3d check``'s exact self-intersection test against ``p3d props``,
today's topology-only ``p3d check``, and pymeshlab's self-intersecting-faces filter.

What it does:

1. Writes closed grid tori as binary STL (``torus.py``, run as a child: the timing parent never
   imports numpy): 1M triangles by default (``--sizes`` for others).
2. Runs, as separate processes, alternating the order run by run:
   - ``p3d check FILE --json``: every check, the self-intersection test included (default);
   - ``p3d check FILE --json --require closed,oriented,outward,manifold,no-degenerate,no-duplicate``:
     the checks without it (what ``p3d check`` did before it);
   - ``p3d props FILE --json``;
   - ``pymeshlab``: load the file and run ``compute_selection_by_self_intersections_per_face``
     (MeshLab's filter), in one ``python`` process; the child also prints the filter's own
     time, so the filter alone is reported beside the whole process.
   Wall time, user+sys CPU time and peak resident memory of each child come from ``os.wait4``.
3. Checks the answers (the torus has no self-intersection: p3d says 0 pairs, MeshLab selects
   0 faces) and prints a markdown table of medians, the ratios the targets are about, the
   memory against the file's size, and the load average before and after.

Usage::

    python benchmarks/self_intersections.py                    # 1M triangles, 5 runs each
    python benchmarks/self_intersections.py --sizes 100000 1000000 --runs 7 --workdir /tmp/si

pymeshlab is a test and benchmark dependency only (``pip install pymeshlab``); without it its
rows are left out.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

from installed import alternated, cache_bytecode

TORUS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "torus.py")
TOPOLOGY_ONLY = "closed,oriented,outward,manifold,no-degenerate,no-duplicate"
MESHLAB = """
import sys, time
import pymeshlab
ms = pymeshlab.MeshSet()
ms.load_new_mesh(sys.argv[1])
start = time.perf_counter()
ms.compute_selection_by_self_intersections_per_face()
took = time.perf_counter() - start
print(ms.current_mesh().selected_face_number(), took)
"""


def grid(triangles: int) -> tuple[int, int]:
    """``(u, v)`` of a grid torus with about ``triangles`` faces (2·u·v), u = 2 v."""
    v = max(int(round((triangles / 4) ** 0.5)), 3)
    return 2 * v, v


def commands(path: str, meshlab: bool) -> dict:
    """name -> (argv, check of (status, stdout))."""
    p3d = [sys.executable, "-m", "p3d_cli"]

    def no_pairs(status, out):
        record = json.loads(out)
        return status == 0 and record["self_intersections"]["count"] == 0 and record["closed"]

    out = {
        "p3d check (all, with self-intersections)": (p3d + ["check", path, "--json"], no_pairs),
        "p3d check (topology only)": (p3d + ["check", path, "--json", "--require", TOPOLOGY_ONLY],
                                      lambda status, out: status == 0 and json.loads(out)["self_intersections"] is None),
        "p3d props": (p3d + ["props", path, "--json"], lambda status, out: status == 0 and json.loads(out)["closed"]),
    }
    if meshlab:
        out["pymeshlab load + filter"] = ([sys.executable, "-c", MESHLAB, path],
                                          lambda status, out: status == 0 and out.split()[0] == "0")
    return out


def time_all(tools: dict, runs: int, env) -> dict:
    results = alternated(tools, runs, env)
    medians = {}
    for name, got in results.items():
        medians[name] = {k: statistics.median(got[k]) for k in ("wall", "cpu", "rss")}
        # pymeshlab's child prints its filter's own time after the count.
        medians[name]["filter"] = (statistics.median(float(t.split()[1]) for t in got["stdout"])
                                   if name.startswith("pymeshlab") else None)
    return medians


def table(rows: dict, runs: int, load: tuple) -> str:
    lines = [f"Whole-process medians of {runs} alternated runs, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} logical CPUs, "
             f"Python {platform.python_version()}; load average {load[0]:.2f} before, {load[1]:.2f} after.", ""]
    for (triangles, size), medians in rows.items():
        lines += [f"**{triangles:,} triangles** (closed grid torus, binary STL, {size / 1e6:.1f} MB):", "",
                  "| command | wall s | user+sys s | peak RSS MB |", "|---|---:|---:|---:|"]
        for name, m in medians.items():
            lines.append(f"| {name} | {m['wall']:.3f} | {m['cpu']:.3f} | {m['rss']:.0f} |")
        check, props = medians["p3d check (all, with self-intersections)"], medians["p3d props"]
        old = medians["p3d check (topology only)"]
        lines += ["", "| ratio | wall | cpu | target |", "|---|---:|---:|---|",
                  f"| check (with the test) / props | {check['wall'] / props['wall']:.2f}× | "
                  f"{check['cpu'] / props['cpu']:.2f}× | ≤ 5 |",
                  f"| the test alone (check with it - check without) / props | "
                  f"{(check['wall'] - old['wall']) / props['wall']:.2f}× | "
                  f"{(check['cpu'] - old['cpu']) / props['cpu']:.2f}× | ≤ 5 |",
                  f"| check (with the test) / check (topology only) | {check['wall'] / old['wall']:.2f}× | "
                  f"{check['cpu'] / old['cpu']:.2f}× | (the test's cost on top of today's check) |"]
        meshlab = medians.get("pymeshlab load + filter")
        if meshlab:
            lines.append(f"| check (with the test) / pymeshlab load + filter | {check['wall'] / meshlab['wall']:.2f}× | "
                         f"{check['cpu'] / meshlab['cpu']:.2f}× | < 1 |")
            lines.append(f"| pymeshlab's filter alone (in process) | {meshlab['filter']:.3f} s | | |")
        lines += ["", f"Peak memory of `p3d check`: {check['rss']:.0f} MB, {check['rss'] * (1 << 20) / size:.2f}× "
                      "the file (target ≤ 3×).", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000_000])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workdir", help="keep the meshes here (default: a temporary directory)")
    args = parser.parse_args(argv)
    workdir = args.workdir or tempfile.mkdtemp(prefix="p3d-si-bench-")
    os.makedirs(workdir, exist_ok=True)
    env = cache_bytecode(os.path.join(workdir, "pycache"))
    meshlab = subprocess.run([sys.executable, "-c", "import pymeshlab"], capture_output=True).returncode == 0
    if not meshlab:
        print("pymeshlab not installed: its rows are left out", file=sys.stderr)
    before = os.getloadavg()[0]
    rows = {}
    for triangles in args.sizes:
        u, v = grid(triangles)
        path = os.path.join(workdir, f"torus-{2 * u * v}.stl")
        if not os.path.exists(path):
            subprocess.run([sys.executable, TORUS, "stl", str(u), str(v), path, "--at", "12.5", "-7.25", "3.0"],
                           check=True)
        rows[(2 * u * v, os.path.getsize(path))] = time_all(commands(path, meshlab), args.runs, env)
    print(table(rows, args.runs, (before, os.getloadavg()[0])))
    if not args.workdir:
        import shutil

        shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
