#!/usr/bin/env python
"""Start-up and install footprint of p3d, before a change and after it, side by side.

What it does:

1. Exports the tree of a git revision (``--before``, default ``main``) and takes this
   checkout as the after; both run from source with this interpreter (same dependencies), with
   their bytecode cached as an install has it (``installed.cache_bytecode``).
2. For ``p3d --help`` and ``p3d props sample_meshes/bracket.stl``, runs each version
   ``--runs`` times, alternating, and reports the median wall time, and the modules each
   imports (``len(sys.modules)`` at exit, interpreter start-up included).
3. With ``--footprint``, installs each version with its core dependencies (no extras) into a
   fresh virtual environment and reports the size of its site-packages (``du``), and the
   biggest packages in it.

Usage::

    python benchmarks/startup.py --runs 15
    python benchmarks/startup.py --runs 15 --footprint
"""

from __future__ import annotations

import argparse
import io
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from installed import cache_bytecode  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
COUNT = ("import atexit, sys; atexit.register(lambda: sys.stderr.write(f'MODULES {len(sys.modules)}\\n')); "
         "sys.argv = ['p3d'] + sys.argv[1:]; from p3d_cli.cli.main import run; run()")
COMMANDS = {"p3d --help": ["--help"], "p3d props part.stl": ["props", "sample_meshes/bracket.stl"]}


def export(revision: str, into: Path) -> Path:
    data = subprocess.run(["git", "-C", str(REPO), "archive", revision], capture_output=True, check=True).stdout
    with tarfile.open(fileobj=io.BytesIO(data)) as tar:
        tar.extractall(into, filter="data") if sys.version_info >= (3, 12) else tar.extractall(into)
    return into


def one(tree: Path, args: list[str], env: dict) -> tuple[float, int]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-c", COUNT, *args], cwd=tree, capture_output=True, text=True,
                          env={**env, "PYTHONPATH": str(tree)})
    wall = time.perf_counter() - start
    modules = int(done.stderr.rsplit("MODULES ", 1)[1].split()[0])
    return wall, modules


def footprint(tree: Path, work: Path, name: str) -> tuple[float, list[tuple[float, str]]]:
    venv = work / f"venv-{name}"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(venv / "bin" / "pip"), "install", "-q", str(tree)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    site = next(venv.glob("lib/python*/site-packages"))
    sizes = []
    for entry in site.iterdir():
        if entry.is_dir() and not entry.name.endswith((".dist-info", "__pycache__")):
            size = sum(f.stat().st_size for f in entry.rglob("*") if f.is_file())
            sizes.append((size / 1e6, entry.name))
    total = sum(f.stat().st_size for f in site.rglob("*") if f.is_file()) / 1e6
    return total, sorted(sizes, reverse=True)[:6]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--before", default="main")
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--footprint", action="store_true")
    options = parser.parse_args()
    env = cache_bytecode()
    with tempfile.TemporaryDirectory() as work:
        trees = {"before": export(options.before, Path(work) / "before"), "after": REPO}
        results = {(cmd, name): [] for cmd in COMMANDS for name in trees}
        modules = {}
        for run in range(options.runs + 1):
            for cmd, args in COMMANDS.items():
                for name in (list(trees) if run % 2 else list(trees)[::-1]):
                    wall, count = one(trees[name], args, env)
                    if run:                                  # the first round fills the caches
                        results[(cmd, name)].append(wall)
                    modules[(cmd, name)] = count
        print(f"{options.runs} alternated runs each, medians; before = {options.before}, load "
              f"{os.getloadavg()[0]:.2f}\n")
        print("| command | modules before | modules after | wall s before | wall s after |")
        print("|---|---|---|---|---|")
        for cmd in COMMANDS:
            b, a = (statistics.median(results[(cmd, n)]) for n in ("before", "after"))
            print(f"| `{cmd}` | {modules[(cmd, 'before')]} | {modules[(cmd, 'after')]} | {b:.3f} | {a:.3f} |")
        if options.footprint:
            print("\n| install (core, no extras) | site-packages MB | largest |")
            print("|---|---|---|")
            for name, tree in trees.items():
                total, largest = footprint(tree, Path(work), name)
                print(f"| {name} | {total:.0f} | " + ", ".join(f"{n} {s:.0f}" for s, n in largest) + " |")


if __name__ == "__main__":
    main()
