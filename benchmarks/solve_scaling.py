"""How `p3d solve` scales: one velocity solve of a chain of N links, and of N independent
pendulums, for N from 1 (or 10) to 10,000.

A chain is one island whose system is block-tridiagonal: the sparse path factorises it in time
linear in N (no dense N×N matrix is formed). Independent pendulums are N islands of one bar each,
solved separately. Both columns should grow about tenfold per tenfold N.

Run: python benchmarks/solve_scaling.py [--max 10000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import math
import time

from p3d_cli.constraints import parse_scene, solve_scene


def chain(n: int, loop: bool = False):
    """A hanging chain of ``n`` ball-jointed links (0.1 m, 1 kg), each moving sideways; with
    ``loop`` the last link is also tied back to the anchor (one redundant closed loop)."""
    bodies = {"anchor": {"fixed": True}}
    constraints = []
    previous = "anchor"
    for i in range(n):
        name = f"link{i}"
        bodies[name] = {"mass": 1.0, "inertia": [1e-3, 1e-3, 1e-4], "position": [0, 0, -0.1 * i - 0.05],
                        "rotation": {"axis": [1, 2, 3], "degrees": 7 * i},
                        "velocity": [math.sin(i), math.cos(i), 0.1], "angular_velocity": [0, 0.3, 0.1 * i % 1]}
        top = [0, 0, 0] if previous == "anchor" else None
        entry = {"type": "ball", "a": previous, "b": name, "attach_b": [0, 0, 0.05]}
        if top is not None:
            entry["attach_a"] = top
        constraints.append(entry)
        previous = name
    if loop:
        constraints.append({"type": "bar", "a": "anchor", "b": previous, "attach_a": [0.3, 0, 0],
                            "attach_b": [0, 0, -0.05]})
    return parse_scene({"bodies": bodies, "constraints": constraints}, f"chain{n}", ".")


def pendulums(n: int):
    """``n`` independent bar pendulums hanging from one fixed frame."""
    bodies = {"frame": {"fixed": True}}
    constraints = []
    for i in range(n):
        name = f"bob{i}"
        bodies[name] = {"mass": 1.0 + i % 3, "inertia": [1e-3, 1e-3, 1e-3], "position": [0.2 * i, 0.3, -1.0],
                        "velocity": [1.0, math.sin(i), 0.5]}
        constraints.append({"type": "bar", "a": "frame", "b": name, "attach_a": [0.2 * i, 0, 0],
                            "attach_b": [0, 0, 0]})
    return parse_scene({"bodies": bodies, "constraints": constraints}, f"pendulums{n}", ".")


def best_time(scene, repeat: int) -> tuple[float, object]:
    best, result = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        result = solve_scene(scene)
        best = min(best, time.perf_counter() - start)
    return best, result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    solve_scene(chain(3))  # warm up imports (scipy) outside the timings
    sizes = [n for n in (1, 10, 100, 1000, 10_000, 100_000) if n <= args.max]
    print(f"{'N':>7}  {'chain':>10}  {'chain+loop':>11}  {'pendulums':>10}   (seconds, best of {args.repeat}; "
          "one velocity solve, scene parsing excluded)")
    for n in sizes:
        row = [f"{n:>7}"]
        if n >= 10:
            t, r = best_time(chain(n), args.repeat)
            assert r.rank == r.equations == 3 * n
            t_loop, r_loop = best_time(chain(n, loop=True), args.repeat)
            assert r_loop.equations == 3 * n + 1
            row += [f"{t:>10.4f}", f"{t_loop:>11.4f}"]
        else:
            row += [f"{'':>10}", f"{'':>11}"]
        t, r = best_time(pendulums(n), args.repeat)
        assert r.islands == n and r.rank == n
        row.append(f"{t:>10.4f}")
        print("  ".join(row), flush=True)


if __name__ == "__main__":
    main()
