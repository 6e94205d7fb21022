#!/usr/bin/env python
"""Whole-process timings of ``p3d repair`` against ``p3d check`` and against admesh's repair of
the same file with the same steps, side by side.

What it does:

1. Generates 1M-triangle grid tori as binary STL (``benchmarks/torus.py``, in a child process:
   the timing parent never imports numpy): closed, open (two faces removed, meeting at a
   corner: two holes), wound inward, and two with many holes (``MESHES``: ``rings``, ten
   loops of 1,000 edges; ``spread``, 9,997 one-face holes).
2. Runs every command as its own process, alternating the commands run by run and rotating
   which goes first, and reads each child's wall time, user+sys CPU time and peak resident
   memory from ``os.wait4``. One untimed warm-up run of each checks its answer: ``p3d repair``
   fixes the open torus with its two holes filled and turns the inward one out whole (and copies
   the closed one); admesh adds the two facets.
3. Prints a markdown table of medians and the ratios the targets are about, with the
   machine's load average before and after.

The same steps: ``p3d repair`` runs its default steps (degenerate and duplicate faces,
orientation, holes, outward; exact vertex matching) and writes binary STL; admesh runs
``-e -f -d`` (exact edge matching, fill holes, fix normal directions) and writes binary STL
(``-b``). By default ``p3d repair`` also checks its output with every check of ``p3d check``,
the exact self-intersection test among them, which admesh has no counterpart of: the rows
``--require topology`` leave that test out (``--require`` with the topology checks only), the
same steps as admesh's. Both measure the mass properties before and after, which admesh does not.

Usage::

    python benchmarks/repair_speed.py                  # 5 runs each, a few minutes
    python benchmarks/repair_speed.py --runs 9 --workdir /tmp/p3d-repair-bench
    python benchmarks/repair_speed.py --meshes rings,spread --runs 3

It needs ``admesh`` on the PATH (Debian/Ubuntu: ``apt-get install admesh``); without it the
admesh rows are left out.
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

#: name -> torus.py's u, v and flags of a 1M-triangle grid torus. ``rings``: every 100th face
#: removed from the 1000 x 500 torus, which takes out five whole rows of quads: ten rings of
#: 1,000 edges, whose flat fillings (fans of slivers) cross the far side of the tube for six
#: of them. ``spread``: every 100th face of the 707 x 707 torus, 9,997 one-face holes.
MESHES = {"closed": (1000, 500, []), "open": (1000, 500, ["--open"]), "inward": (1000, 500, ["--inward"]),
          "rings": (1000, 500, ["--holes", "0.01"]), "spread": (707, 707, ["--holes", "0.01"])}

TORUS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "torus.py")

#: The checks of p3d check but the self-intersection test (admesh's steps have no counterpart).
TOPOLOGY = "closed,oriented,outward,manifold,no-degenerate,no-duplicate"


def commands(paths: dict, out: str, admesh: str | None) -> dict:
    """name -> (argv, check of (status, stdout))."""
    p3d = [sys.executable, "-m", "p3d_cli"]

    def checked(ok: bool):
        return lambda status, text: status == (0 if ok else 1) and json.loads(text)["ok"] is ok

    def repaired(step: str, key: str, value: int, written: str = "written", fixed: bool = True):
        def ok(status, text):
            record = json.loads(text)
            counts = {s["step"]: s["counts"] for s in record["steps"]}
            return (status == (0 if fixed else 1) and record["fixed"] is fixed and record["written"] == written
                    and (step == "" or counts[step][key] == value))
        return ok

    answers = {"open": repaired("holes", "holes_filled", 2), "inward": repaired("outward", "faces_flipped", 1_000_000),
               "closed": repaired("", "", 0, "copied"),
               # Four rings filled; six left (their fillings would cross the tube): not fixed.
               "rings": repaired("holes", "holes_left", 6, fixed=False),
               "spread": repaired("holes", "holes_filled", 9_997)}
    tools = {}
    for name in paths:
        tools[f"p3d check {name}"] = (p3d + ["check", paths[name], "--json"], checked(name == "closed"))
        tools[f"p3d repair {name}"] = (p3d + ["repair", paths[name], "-o", out, "--json"], answers[name])
        tools[f"p3d repair {name} --require topology"] = (
            p3d + ["repair", paths[name], "-o", out, "--json", "--require", TOPOLOGY], answers[name])
    if admesh:
        def added(n: int | None):
            # admesh fills every loop its own way: only the count of the open torus is known.
            return lambda status, text: status == 0 and (
                f"Facets added          :     {n}" in text if n is not None else "Facets added" in text)

        known = {"open": 2, "closed": 0, "inward": 0}
        for name in paths:
            tools[f"admesh -e -f -d {name}"] = ([admesh, "-e", "-f", "-d", "-b", out, paths[name]],
                                                added(known.get(name)))
    return tools


def table(medians: dict, runs: int, load: tuple) -> str:
    lines = [f"Whole-process medians of {runs} alternated runs, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
             f"{platform.processor() or platform.machine()}, {os.cpu_count()} logical CPUs, "
             f"Python {platform.python_version()}; load average {load[0]:.2f} before, {load[1]:.2f} after.",
             "", "| command (1M-triangle torus) | wall s | user+sys s | peak RSS MB |", "|---|---:|---:|---:|"]
    for name, m in medians.items():
        lines.append(f"| `{name}` | {m['wall']:.2f} | {m['cpu']:.2f} | {m['rss']:.0f} |")
    lines += ["", "| ratio | wall | cpu | target |", "|---|---:|---:|---|"]

    def ratio(label, a, b, target):
        if a in medians and b in medians:
            lines.append(f"| {label} | {medians[a]['wall'] / medians[b]['wall']:.2f}× | "
                         f"{medians[a]['cpu'] / medians[b]['cpu']:.2f}× | {target} |")

    for name in MESHES:
        ratio(f"repair / check ({name})", f"p3d repair {name}", f"p3d check {name}", "≤ 3")
    for name in MESHES:
        ratio(f"repair --require topology / admesh -e -f -d ({name}): the same steps",
              f"p3d repair {name} --require topology", f"admesh -e -f -d {name}", "< 1")
    for name in MESHES:
        ratio(f"repair / admesh -e -f -d ({name}): with the self-intersection test", f"p3d repair {name}",
              f"admesh -e -f -d {name}", "(none)")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workdir", help="keep the meshes here (default: a temporary directory)")
    parser.add_argument("--meshes", default=",".join(MESHES),
                        help=f"comma-separated, of {', '.join(MESHES)} (default: all)")
    args = parser.parse_args(argv)
    workdir = args.workdir or tempfile.mkdtemp(prefix="p3d-repair-bench-")
    os.makedirs(workdir, exist_ok=True)
    env = cache_bytecode(os.path.join(workdir, "pycache"))
    paths = {}
    for name in args.meshes.split(","):
        if name not in MESHES:
            parser.error(f"--meshes: unknown mesh {name!r}; choose among {', '.join(MESHES)}")
        u, v, flags = MESHES[name]
        paths[name] = os.path.join(workdir, f"torus-1m-{name}.stl")
        if not os.path.exists(paths[name]):
            subprocess.run([sys.executable, TORUS, "stl", str(u), str(v), paths[name], "--at", "12.5", "-7.25", "3.0",
                            *flags], check=True)
    admesh = shutil.which("admesh")
    if admesh is None:
        print("admesh not found: its rows are left out", file=sys.stderr)
    before = os.getloadavg()[0]
    timed = alternated(commands(paths, os.path.join(workdir, "out.stl"), admesh), args.runs, env)
    medians = {name: {key: statistics.median(values) for key, values in got.items() if key != "stdout"}
               for name, got in timed.items()}
    print(table(medians, args.runs, (before, os.getloadavg()[0])))
    if not args.workdir:
        shutil.rmtree(workdir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
