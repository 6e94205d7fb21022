"""Stepping cost: ``p3d solve --steps N --dt DT`` before and after the array-based step, and MuJoCo.

For each of examples/pendulum.yaml, chain.yaml and four_bar.yaml this runs, alternately and
``--repeat`` times:

- **before**: ``p3d solve`` of the commit before the array-based step (``--before``, default
  1141c9c), extracted with ``git archive`` into a temporary folder and run from there;
- **after**: ``p3d solve`` of this working tree;
- **MuJoCo**: the same scene built as MJCF here (a ball-jointed bob; five ball-jointed links; a
  four-bar of hinges closed by a ``connect`` equality), stepped with its default Euler
  integrator at the same ``dt``, in this process.

p3d runs are separate processes, timed by the CPU time of children (``resource.getrusage``), so
they include the interpreter's start-up and imports (about 0.15 s). Both trees are byte-compiled
first (``compileall``), as an installed package is: with ``PYTHONDONTWRITEBYTECODE`` set (as in
some CI and container set-ups) each run would otherwise compile ~45 modules from source, ~0.05 s
a run for old and new alike (``--no-compile`` measures that way). MuJoCo's time is
``time.process_time`` around its stepping loop only. Reported: CPU seconds per simulated second
(medians), the ratios, the joint closure (p3d's ``max_position_error``; MuJoCo's largest
distance between the four-bar's two halves of the closing joint), and the machine load.

Run ``pip install -e '.[bench]'`` first (MuJoCo is in the ``bench`` extra).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ("pendulum", "chain", "four_bar")

RUNNER = "import sys; from p3d_cli.cli.main import cli; sys.argv[0] = 'p3d'; cli()"
CHECK = "import p3d_cli, sys; sys.stdout.write(p3d_cli.__file__)"

MJCF = {
    # A 1 kg bob 1 m from the pivot at 30°, 1 m/s along x (p3d's bar leaves the bob free to spin;
    # here it turns with the rod, which costs MuJoCo nothing).
    "pendulum": """
<mujoco><option timestep="{dt}"/>
  <worldbody><body name="bob" euler="0 -30 0"><joint type="ball"/>
    <geom type="sphere" size="0.03" pos="0 0 -1" mass="1"/></body></worldbody></mujoco>""",
    # Five 20 cm links of 0.5 kg hanging on ball joints; the last one struck at 1 m/s.
    "chain": """
<mujoco><option timestep="{dt}"/><worldbody>
  <body name="l1" pos="0 0 -0.1"><joint type="ball" pos="0 0 0.1"/>{link}
   <body name="l2" pos="0 0 -0.2"><joint type="ball" pos="0 0 0.1"/>{link}
    <body name="l3" pos="0 0 -0.2"><joint type="ball" pos="0 0 0.1"/>{link}
     <body name="l4" pos="0 0 -0.2"><joint type="ball" pos="0 0 0.1"/>{link}
      <body name="l5" pos="0 0 -0.2"><joint type="ball" pos="0 0 0.1"/>{link}
  </body></body></body></body></body></worldbody></mujoco>""",
    # Ground pivots A = (0,0,0), D = (1,0,0); B = (0.2,0,0.3), C = (0.9,0,0.5); aluminium bars of
    # 2 × 2 cm section; hinges along y; the loop closed at D by a connect equality.
    "four_bar": """
<mujoco><option timestep="{dt}"/><worldbody>
  <body name="crank"><joint name="a" type="hinge" axis="0 1 0"/>
   <geom type="box" fromto="0 0 0 0.2 0 0.3" size="0.01 0.01" density="2700"/>
   <body name="coupler" pos="0.2 0 0.3"><joint type="hinge" axis="0 1 0"/>
    <geom type="box" fromto="0 0 0 0.7 0 0.2" size="0.01 0.01" density="2700"/>
    <body name="rocker" pos="0.7 0 0.2"><joint type="hinge" axis="0 1 0"/>
     <geom type="box" fromto="0 0 0 0.1 0 -0.5" size="0.01 0.01" density="2700"/>
     <site name="d" pos="0.1 0 -0.5"/>
  </body></body></body></worldbody>
  <equality><connect body1="rocker" body2="world" anchor="0.1 0 -0.5"/></equality></mujoco>""",
}
LINK = ('<inertial pos="0 0 0" mass="0.5" diaginertia="1.7e-3 1.7e-3 1.0e-4"/>'
        '<geom type="capsule" fromto="0 0 0.1 0 0 -0.1" size="0.01" contype="0" conaffinity="0"/>')


def p3d_run(python_path: str | None, name: str, steps: int, dt: float) -> tuple[float, float]:
    """(CPU seconds of one ``p3d solve --json`` child, its max_position_error)."""
    # Run outside the repository (the current folder comes first on sys.path), so that
    # PYTHONPATH decides which p3d_cli is imported.
    env = dict(os.environ)
    if python_path:
        env["PYTHONPATH"] = python_path
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run([sys.executable, "-c", RUNNER, "solve", str(ROOT / "examples" / f"{name}.yaml"),
                          "--steps", str(steps), "--dt", str(dt), "--json"],
                         env=env, cwd=tempfile.gettempdir(), capture_output=True, text=True, check=True).stdout
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, float(json.loads(out)["max_position_error"])


def mujoco_run(name: str, steps: int, dt: float) -> tuple[float, float]:
    """(CPU seconds of ``steps`` MuJoCo steps, the largest closure gap of the four-bar)."""
    import mujoco

    model = mujoco.MjModel.from_xml_string(MJCF[name].format(dt=dt, link=LINK))
    data = mujoco.MjData(model)
    if name == "pendulum":
        data.qvel[:] = [0.0, -np.cos(np.radians(30)), 0.0]    # the tangential part of 1 m/s along x
    elif name == "chain":
        data.qvel[-3:] = [0.0, -10.0, 0.0]                    # the last link's centre at 1 m/s along x
    else:
        data.qvel[0] = 2.0                                    # the crank at 2 rad/s
    mujoco.mj_forward(model, data)
    gap = 0.0
    start = time.process_time()
    if name == "four_bar":
        d = np.array([1.0, 0.0, 0.0])
        for _ in range(steps):
            mujoco.mj_step(model, data)
            gap = max(gap, float(np.linalg.norm(data.site_xpos[0] - d)))
    else:
        for _ in range(steps):
            mujoco.mj_step(model, data)
    return time.process_time() - start, gap


def extract(commit: str, folder: str) -> str:
    """The package at ``commit``, unpacked into ``folder``; returns the folder."""
    archive = subprocess.run(["git", "archive", commit, "p3d_cli"], cwd=ROOT, capture_output=True, check=True).stdout
    subprocess.run(["tar", "-x", "-C", folder], input=archive, check=True)
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=10_000)
    parser.add_argument("--dt", type=float, default=0.001)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--before", default="1141c9c", help="commit of the old stepping code")
    parser.add_argument("--no-before", action="store_true", help="skip the old code (slow)")
    parser.add_argument("--no-compile", action="store_true", help="do not byte-compile the two trees first")
    args = parser.parse_args()
    simulated = args.steps * args.dt
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory() as folder:
        old = None if args.no_before else extract(args.before, folder)
        if not args.no_compile:
            for tree in ([old] if old else []) + [str(ROOT / "p3d_cli")]:
                subprocess.run([sys.executable, "-m", "compileall", "-q", tree], check=True, capture_output=True)
        if old:
            env = dict(os.environ, PYTHONPATH=old)
            used = subprocess.run([sys.executable, "-c", CHECK], env=env, cwd=tempfile.gettempdir(),
                                  capture_output=True, text=True, check=True).stdout
            assert used.startswith(old), f"the old code did not load: {used}"
        rows = []
        for name in EXAMPLES:
            times = {"before": [], "after": [], "mujoco": []}
            closure = {}
            for _ in range(args.repeat):          # alternate, so that load changes hit all alike
                if old:
                    cpu, closure["before"] = p3d_run(old, name, args.steps, args.dt)
                    times["before"].append(cpu)
                cpu, closure["after"] = p3d_run(None, name, args.steps, args.dt)
                times["after"].append(cpu)
                cpu, closure["mujoco"] = mujoco_run(name, args.steps, args.dt)
                times["mujoco"].append(cpu)
            med = {k: statistics.median(v) / simulated for k, v in times.items() if v}
            rows.append((name, med, closure))
    load_end = os.getloadavg()
    print(f"CPU seconds per simulated second, median of {args.repeat}; {args.steps} steps of dt = {args.dt}; "
          f"{'source' if args.no_compile else 'byte-compiled'} trees")
    print(f"{'scene':10s} {'before':>8s} {'after':>8s} {'MuJoCo':>8s} {'before/after':>13s} {'after/MuJoCo':>13s}"
          f" {'closure p3d':>12s} {'closure MuJoCo':>15s}")
    for name, med, closure in rows:
        before = f"{med['before']:8.3f}" if "before" in med else f"{'-':>8s}"
        speedup = f"{med['before'] / med['after']:13.1f}" if "before" in med else f"{'-':>13s}"
        mj_gap = f"{closure['mujoco']:15.2e}" if name == "four_bar" else f"{'-':>15s}"
        print(f"{name:10s} {before} {med['after']:8.3f} {med['mujoco']:8.4f} {speedup}"
              f" {med['after'] / med['mujoco']:13.0f} {closure['after']:12.1e} {mj_gap}")
    print(f"load average (1, 5, 15 min): start {load_start[0]:.2f} {load_start[1]:.2f} {load_start[2]:.2f}, "
          f"end {load_end[0]:.2f} {load_end[1]:.2f} {load_end[2]:.2f}; {os.cpu_count()} CPUs")


if __name__ == "__main__":
    main()
