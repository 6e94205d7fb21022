#!/usr/bin/env python
"""CPU of a CI gate over the real meshes: `p3d check` then `p3d diff` (two reads of each file)
against `p3d diff --require all` (one read: both on the same load), and `p3d check` alone.

What it does:

1. Lists the real meshes (``../shared/real-meshes`` beside the repository, or ``--meshes``)
   ``--copies`` times over in a list file (default 20: 10 files x 20 = 200 inputs, the size of
   the gate issue 24 measured), and records a baseline with ``p3d props --json``.
2. Runs each gate as its own processes, ``--runs`` times, alternating the order run by run,
   all with ``--jobs 1`` (CPU time, not wall time, is the figure: workers would only spread
   it), and reads each child's user+sys CPU time from ``os.wait4``.
3. Prints a markdown table of medians and the ratios the target is about: the one-read gate
   against check alone and against check + diff.

Usage::

    python benchmarks/ci_gate.py                 # 5 runs each
    python benchmarks/ci_gate.py --runs 9 --copies 20
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
MESHES = REPO.parent / "shared" / "real-meshes"
EXTENSIONS = (".stl", ".obj", ".ply", ".off")


def timed(args: list[str], cwd: Path) -> tuple[float, int]:
    """User+sys CPU seconds of one process, and its exit status."""
    process = subprocess.Popen([sys.executable, "-m", "p3d_cli", *args], cwd=cwd,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(process.pid, 0)
    return usage.ru_utime + usage.ru_stime, os.waitstatus_to_exitcode(status)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--meshes", type=Path, default=MESHES)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--copies", type=int, default=20)
    options = parser.parse_args()
    files = sorted(str(p) for p in options.meshes.iterdir() if p.suffix.lower() in EXTENSIONS)
    with tempfile.TemporaryDirectory() as work:
        work_dir = Path(work)
        listing = work_dir / "list.txt"
        listing.write_text("".join(f"{f}\n" for f in files * options.copies))
        baseline = work_dir / "baseline.ndjson"
        made = subprocess.run([sys.executable, "-m", "p3d_cli", "props", *files, "--json", "--jobs", "1"],
                              cwd=work_dir, capture_output=True, text=True)
        baseline.write_text(made.stdout)
        common = ["--files-from", str(listing), "--jobs", "1"]
        gates = {
            "check": [["check", *common]],
            "diff": [["diff", str(baseline), *common]],
            "check, then diff": [["check", *common], ["diff", str(baseline), *common]],
            "diff --require all": [["diff", str(baseline), *common, "--require", "all"]],
        }
        seconds: dict[str, list[float]] = {name: [] for name in gates}
        for run in range(options.runs + 1):                      # the first round warms the caches
            names = list(gates)[run % len(gates):] + list(gates)[:run % len(gates)]
            for name in names:
                total = sum(timed(args, work_dir)[0] for args in gates[name])
                if run:
                    seconds[name].append(total)
    median = {name: statistics.median(values) for name, values in seconds.items()}
    print(f"{len(files)} real meshes x {options.copies} = {len(files) * options.copies} inputs, "
          f"--jobs 1, {options.runs} runs, medians of user+sys CPU seconds; load {os.getloadavg()[0]:.2f}\n")
    print("| gate | CPU s | / check alone |")
    print("|---|---|---|")
    for name, value in median.items():
        print(f"| `{name}` | {value:.2f} | {value / median['check']:.2f} |")
    print(f"\none read against two: {median['diff --require all'] / median['check, then diff']:.2f}; "
          f"against check alone plus the comparison (diff): "
          f"{median['diff --require all'] / (median['check'] + median['diff']):.2f}")


if __name__ == "__main__":
    main()
