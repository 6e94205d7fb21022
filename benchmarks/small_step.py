#!/usr/bin/env python
"""What the small-scene step buys: ``solve_scene`` of each example stepped on the small-scene
path (``constraints/small_step.py``, Python floats) and on the array path every scene can take
(``World``, the small path switched off by making ``small_step.fits`` say no), side by side.

For each of examples/pendulum.yaml, chain.yaml, four_bar.yaml and hinged_door.yaml this loads
the scene once, then alternates the two paths ``--repeat`` times, each stepping ``--steps``
steps of ``--dt`` in this process (``time.process_time``, so start-up and loading are left out).
Reported: CPU milliseconds per 1,000 steps (medians), the ratio array / small, and the largest
difference between the two paths' final positions and velocities (the paths agree to rounding,
not to the bit, so dropping one changes ``p3d solve --json`` in its last digits).

Usage::

    python benchmarks/small_step.py --steps 2000 --repeat 5

With ``PYTHONPATH`` set to another source tree, that tree's p3d_cli is measured instead.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

from p3d_cli.constraints import load_scene, small_step, solve_scene

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
SCENES = ("pendulum", "chain", "four_bar", "hinged_door")


def run(scene, steps: int, dt: float, small: bool):
    """``(cpu seconds, final state)`` of one stepped solve on the chosen path."""
    fits = small_step.fits
    if not small:
        small_step.fits = lambda world: False
    try:
        start = time.process_time()
        result = solve_scene(scene, steps=steps, dt=dt)
        cpu = time.process_time() - start
    finally:
        small_step.fits = fits
    state = np.array([[*b.position, *b.velocity, *b.angular_velocity] for b in result.bodies], dtype=np.float64)
    return cpu, state


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--dt", type=float, default=0.001)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f}; {args.steps} steps of {args.dt}, medians of {args.repeat}")
    print(f"{'scene':<12} {'small ms/1k':>12} {'array ms/1k':>12} {'array/small':>12} {'max |diff|':>11}")
    for name in SCENES:
        scene = load_scene(str(EXAMPLES / f"{name}.yaml"))
        times: dict[bool, list[float]] = {True: [], False: []}
        states = {}
        for _ in range(args.repeat):
            for small in (True, False):
                cpu, states[small] = run(scene, args.steps, args.dt, small)
                times[small].append(cpu)
        small_ms, array_ms = (1000 * statistics.median(times[k]) / (args.steps / 1000) for k in (True, False))
        diff = float(np.max(np.abs(states[True] - states[False])))
        print(f"{name:<12} {small_ms:>12.1f} {array_ms:>12.1f} {array_ms / small_ms:>12.2f} {diff:>11.1e}")


if __name__ == "__main__":
    main()
