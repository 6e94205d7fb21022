#!/usr/bin/env python
"""Scene formats against their numpy floor: ``p3d props`` on GLB and 3MF (issue 32, items 1 and 3).

For each size, one closed grid torus (``torus.py``) is written as binary STL and converted by
trimesh to GLB (one mesh, one primitive, no transforms) and to 3MF (one object, millimetres).
Then, as whole processes, run by run alternated after one checked warm-up run each:

- ``p3d props FILE --json`` (its volume must equal the floor's, in the file's unit);
- ``benchmarks/floor.py FILE``: the least a numpy program does for the same answer (GLB: the
  accessors read straight from the binary chunk; 3MF: unzip, regular expressions over the XML
  text, numpy's float parser; then the same block integration as the other floors).

Prints a markdown table of medians (CPU = user + system), the ratio p3d / floor (target: GLB
at most 1.5, the streaming floor's target for binary files; 3MF, a text format, at most 2), and
the load average at the start and the end.

Usage::

    python benchmarks/scene_floor.py                     # 1M triangles, 5 runs
    python benchmarks/scene_floor.py --sizes 1000000 4000000 --runs 3 --workdir /tmp/scenes
    python benchmarks/scene_floor.py --sizes 16000000 --formats glb --runs 3 --workdir /tmp/scenes
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

from installed import alternated, cache_bytecode

HERE = os.path.dirname(os.path.abspath(__file__))
#: The ratio p3d / floor each format must stay within.
TARGETS = {"glb": 1.5, "3mf": 2.0}


def write_meshes(n: int, workdir: str, formats=tuple(TARGETS)) -> dict[str, str]:
    """GLB and 3MF files (``formats``) of a closed torus of about ``n`` triangles; name -> path. Written by
    child processes: a large parent would raise every child's peak RSS (Linux copies the
    parent's high-water mark into a forked child)."""
    u = int(round((n / 2) ** 0.5 * 2 ** 0.5))
    v = n // (2 * u)
    stl = os.path.join(workdir, f"torus_{n}.stl")
    if not os.path.exists(stl):
        subprocess.run([sys.executable, os.path.join(HERE, "torus.py"), "stl", str(u), str(v), stl], check=True)
    out = {}
    for fmt in formats:
        path = os.path.join(workdir, f"torus_{n}.{fmt}")
        if not os.path.exists(path):
            subprocess.run([sys.executable, "-c", "import sys, trimesh; trimesh.load(sys.argv[1]).export(sys.argv[2])",
                            stl, path], check=True)
        out[fmt] = path
    return out


def tools(path: str, fmt: str) -> dict:
    """name -> (argv, check of (status, stdout))."""
    floor = [sys.executable, os.path.join(HERE, "floor.py"), path]
    expected = float(subprocess.run(floor, capture_output=True, text=True, check=True).stdout)
    # 3MF is in millimetres: p3d reports SI, the floor the file's numbers.
    factor = 1e-9 if fmt == "3mf" else 1.0

    def p3d_ok(status, text):
        return status == 0 and abs(json.loads(text)["volume"] - expected * factor) <= 1e-9 * abs(expected * factor)

    def floor_ok(status, text):
        return status == 0 and float(text) == expected

    return {f"p3d props {fmt}": ([sys.executable, "-m", "p3d_cli", "props", path, "--json"], p3d_ok),
            f"floor {fmt}": (floor, floor_ok)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000_000])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workdir")
    parser.add_argument("--formats", nargs="+", choices=tuple(TARGETS), default=list(TARGETS))
    args = parser.parse_args(argv)
    workdir = args.workdir or tempfile.mkdtemp(prefix="p3d-scenes-")
    os.makedirs(workdir, exist_ok=True)
    env = cache_bytecode()
    start = os.getloadavg()[0]
    print(f"Whole-process medians of {args.runs} alternated runs, "
          f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; {platform.machine()}, "
          f"{os.cpu_count()} logical CPUs, Python {platform.python_version()}. "
          f"Command: `python benchmarks/scene_floor.py {' '.join(argv if argv is not None else sys.argv[1:])}`."
          f" Load average {start:.2f} at the start.\n")
    print("| format | triangles | p3d cpu s | floor cpu s | p3d / floor | p3d wall s | floor wall s "
          "| p3d RSS MB | floor RSS MB | target |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for n in args.sizes:
        paths = write_meshes(n, workdir, args.formats)
        for fmt, path in paths.items():
            timed = alternated(tools(path, fmt), args.runs, env)
            p, f = timed[f"p3d props {fmt}"], timed[f"floor {fmt}"]
            med = {key: (statistics.median(p[key]), statistics.median(f[key])) for key in ("cpu", "wall", "rss")}
            ratio = med["cpu"][0] / med["cpu"][1]
            print(f"| {fmt} | {n:,} | {med['cpu'][0]:.3f} | {med['cpu'][1]:.3f} | **{ratio:.2f}×** "
                  f"| {med['wall'][0]:.3f} | {med['wall'][1]:.3f} | {med['rss'][0]:.0f} | {med['rss'][1]:.0f} "
                  f"| ≤ {TARGETS[fmt]:g} {'✓' if ratio <= TARGETS[fmt] else '✗'} |")
    print(f"\nLoad average {os.getloadavg()[0]:.2f} at the end.")
    if not args.workdir:
        shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
