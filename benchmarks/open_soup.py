#!/usr/bin/env python
"""Whole-process timings of ``p3d props`` on a closed 1M-face mesh against the same faces as a
far-away soup of loose triangles (every side a boundary edge: 3M of them).

What it does:

1. Generates, in a child process (the timing parent never imports numpy), a grid torus of
   1M triangles at (1e8, 1e8, 0) as binary little-endian PLY with double coordinates (float32
   cannot hold a part of size 8 at 1e8), and the same triangles each shrunk towards its own
   centroid by 2^-20, so that no two share an edge: a soup whose 3M sides are all boundary.
   Every triangle has its own three vertices in both files, so they read alike.
2. Runs ``python -m p3d_cli props FILE --json`` on each as its own process, alternating the
   cases run by run (and, with ``--baseline``, the two source trees), and reads each child's
   wall time, user+sys CPU time and peak RSS from ``os.wait4``. One untimed warm-up run each.
3. Prints a markdown table of medians, the soup's extra time per boundary side, and the
   machine's load average before and after.

Usage::

    python benchmarks/open_soup.py                       # 5 runs each, about a minute
    git worktree add /tmp/p3d-before <commit>
    python benchmarks/open_soup.py --baseline /tmp/p3d-before --baseline-runs 1

The soup's figure before the boundary terms were streamed (commit e4a6c67) is over a minute a
run, so ``--baseline-runs`` defaults to 1 for the soup there.
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
from pathlib import Path

from installed import cache_bytecode, run_once

HERE = Path(__file__).resolve().parent.parent

TORUS = str(Path(__file__).resolve().parent / "torus.py")  # the mesh writer, run as a child


def cases(paths: dict, trees: dict, env: dict, baseline_runs: int, runs: int) -> dict:
    """name -> (argv, environment, runs)."""
    out = {}
    for tree, root in trees.items():
        tree_env = dict(env, PYTHONPATH=str(root), OPENBLAS_NUM_THREADS="1")
        for mesh in ("closed", "soup"):
            count = baseline_runs if tree == "before" and mesh == "soup" else runs
            out[f"{tree}: props 1M {mesh}"] = (
                [sys.executable, "-m", "p3d_cli", "props", paths[mesh], "--json"], tree_env, count)
    return out


def time_all(tools: dict) -> dict:
    results = {name: {"wall": [], "cpu": [], "rss": []} for name in tools}
    names = list(tools)
    for name in names:                              # warm-up, and the answer check
        argv, env, _ = tools[name]
        *_, status, text = run_once(argv, env)
        if status != 0 or json.loads(text)["closed"] is not name.endswith("closed"):
            raise SystemExit(f"{name}: unexpected answer (exit {status}): {text[:300]}")
    for r in range(max(runs for *_, runs in tools.values())):
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            argv, env, runs = tools[name]
            if r >= runs:
                continue
            wall, cpu, rss, _, _ = run_once(argv, env)
            results[name]["wall"].append(wall)
            results[name]["cpu"].append(cpu)
            results[name]["rss"].append(rss)
    return {name: {k: statistics.median(v) for k, v in got.items()} | {"runs": len(got["cpu"])}
            for name, got in results.items()}


def table(medians: dict, load: tuple) -> str:
    lines = [f"Whole-process medians, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} logical CPUs, "
             f"Python {platform.python_version()}; load average {load[0]:.2f} before, {load[1]:.2f} after.",
             "", "| command | runs | wall s | user+sys s | peak RSS MB |", "|---|---:|---:|---:|---:|"]
    for name, m in medians.items():
        lines.append(f"| `{name}` | {m['runs']} | {m['wall']:.3f} | {m['cpu']:.3f} | {m['rss']:.0f} |")
    lines.append("")
    for tree in ("before", "after"):
        closed, soup = medians.get(f"{tree}: props 1M closed"), medians.get(f"{tree}: props 1M soup")
        if closed and soup:
            extra = soup["cpu"] - closed["cpu"]
            lines.append(f"- {tree}: the soup costs {extra:.2f} s CPU more than the closed mesh "
                         f"({soup['cpu'] / closed['cpu']:.1f}×), {extra / 3e6 * 1e6:.2f} µs per boundary side.")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--baseline", help="a source tree of p3d to time side by side (e.g. a git worktree)")
    parser.add_argument("--baseline-runs", type=int, default=1, help="runs of the baseline's soup case")
    parser.add_argument("--workdir", help="keep the meshes here (default: a temporary directory)")
    args = parser.parse_args(argv)
    env = cache_bytecode()
    work = Path(args.workdir or tempfile.mkdtemp(prefix="p3d-soup-"))
    work.mkdir(parents=True, exist_ok=True)
    paths = {}
    for mesh in ("closed", "soup"):
        path = work / f"torus-1m-{mesh}.ply"
        if not path.exists():
            subprocess.run([sys.executable, TORUS, "ply", "1000", "500", str(path), "--at", "1e8", "1e8", "0"]
                           + (["--soup"] if mesh == "soup" else []), check=True)
        paths[mesh] = str(path)
    trees = {"after": HERE}
    if args.baseline:
        trees = {"before": Path(args.baseline).resolve(), **trees}
    load_before = os.getloadavg()[0]
    medians = time_all(cases(paths, trees, env, args.baseline_runs, args.runs))
    print(table(medians, (load_before, os.getloadavg()[0])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
