"""Record the stepping reference: run ``solve_scene`` on the examples and store the states.

Run from the repository root (``python tests/constraints/record_stepping_reference.py``). The
stored file was produced by the stepping code as it was before the array-based step (commit
1141c9c); ``test_stepping_reference.py`` checks today's code against it. Re-running it with
newer code overwrites the reference, so do that only on purpose.
"""

from __future__ import annotations

import json
import pathlib
import sys

import numpy as np

from p3d_cli.constraints import load_scene, solve_scene

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = pathlib.Path(__file__).resolve().parent / "data" / "stepping_reference.json"
EXAMPLES = ("pendulum", "chain", "four_bar", "hinged_door")
STEPS, DT, EVERY = 10000, 1e-3, 1000


def state(bodies) -> dict:
    """Centre of mass (or origin), quaternion, velocity and angular velocity of every body."""
    out = {}
    for b in bodies:
        com = b.center_of_mass if b.center_of_mass is not None else b.position
        out[b.name] = [com.tolist(), b.rotation.tolist(), b.velocity.tolist(), b.angular_velocity.tolist()]
    return out


def record(name: str) -> dict:
    scene = load_scene(str(ROOT / "examples" / f"{name}.yaml"))
    snapshots = []

    def on_step(t, bodies):
        step = int(round(t / DT))
        if step % EVERY == 0:
            snapshots.append({"step": step, "bodies": state(bodies)})

    result = solve_scene(scene, steps=STEPS, dt=DT, on_step=on_step)
    return {
        "steps": STEPS, "dt": DT, "snapshots": snapshots,
        "rank": result.rank, "equations": result.equations, "islands": result.islands,
        "kinetic_energy": list(result.kinetic_energy),
        "momentum": [m.tolist() for m in result.momentum],
        "angular_momentum": [m.tolist() for m in result.angular_momentum],
        "max_position_error": result.max_position_error,
        "impulses": [np.atleast_1d(c.impulse).tolist() for c in result.constraints],
        "errors": [c.error for c in result.constraints],
        "position_errors": [c.position_error for c in result.constraints],
    }


if __name__ == "__main__":
    # The four-bar's "nudged" run (one initial velocity changed by 1e-15) and
    # generated_reference.json were recorded by the old algorithm's copy, since retired: they
    # are kept as they are.
    names = sys.argv[1:] or EXAMPLES
    data = json.loads(OUT.read_text()) if OUT.exists() else {}
    for name in names:
        nudged = data.get(name, {}).get("nudged")
        data[name] = record(name)
        if nudged is not None:
            data[name]["nudged"] = nudged
    OUT.write_text(json.dumps(data, indent=1))
