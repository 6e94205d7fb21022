"""How long ``p3d robot check`` takes as a CI gate, side by side with loading the same robot in MuJoCo.

Writes a 30-link robot of primitives (three collision geoms per link, declared inertials) as
URDF and as MJCF, then alternates, RUNS times each:

- ``p3d robot check robot.urdf`` (a fresh process: start-up included, as in CI);
- ``p3d robot check robot.xml``;
- ``python -c "mujoco.MjModel.from_xml_path('robot.xml')"``: MuJoCo's compiler, which also
  rejects impossible inertias (the peer a MuJoCo user would run).

and prints the median wall time and the median CPU time of the child process
(``resource.getrusage(RUSAGE_CHILDREN)`` differences), the ratios, and the machine load.

Usage::

    python benchmarks/robot_check.py [RUNS]
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from installed import cache_bytecode

LINKS = 30


def write_robot(folder: Path) -> tuple[Path, Path]:
    links, joints, bodies = [], [], []
    r, length, mass = 0.05, 0.3, 2.0
    ixx, izz = mass * (3 * r * r + length * length) / 12, mass * r * r / 2
    for i in range(LINKS):
        links.append(f"""  <link name="l{i}">
    <collision><origin xyz="0 0 0.15" rpy="0 0 0.1"/><geometry><cylinder radius="{r}" length="{length}"/></geometry></collision>
    <collision><origin xyz="0 0 0.3"/><geometry><sphere radius="0.04"/></geometry></collision>
    <collision><origin xyz="0.05 0 0.1"/><geometry><box size="0.02 0.04 0.06"/></geometry></collision>
    <inertial><origin xyz="0 0 0.16"/><mass value="{mass}"/>
      <inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{ixx}" iyz="0" izz="{izz}"/></inertial>
  </link>""")
        if i:
            joints.append(f'  <joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
                          '<origin xyz="0 0 0.3"/><axis xyz="0 1 0"/>'
                          '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
        bodies.append(f"""<body name="l{i}" pos="0 0 {0.3 if i else 0}"><joint type="hinge" axis="0 1 0"/>
<geom type="cylinder" size="{r} {length / 2}" pos="0 0 0.15" euler="0 0 0.1"/>
<geom type="sphere" size="0.04" pos="0 0 0.3"/><geom type="box" size="0.01 0.02 0.03" pos="0.05 0 0.1"/>
<inertial pos="0 0 0.16" mass="{mass}" diaginertia="{ixx} {ixx} {izz}"/>""")
    urdf = folder / "robot.urdf"
    urdf.write_text('<robot name="r">\n' + "\n".join(links + joints) + "\n</robot>\n")
    mjcf = folder / "robot.xml"
    mjcf.write_text('<mujoco><compiler angle="radian"/><worldbody>\n' + "\n".join(bodies) + "</body>" * LINKS
                    + "\n</worldbody></mujoco>\n")
    return urdf, mjcf


def timed(command: list[str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    cache_bytecode()
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 7
    folder = Path(tempfile.mkdtemp())
    urdf, mjcf = write_robot(folder)
    p3d = [sys.executable, "-m", "p3d_cli", "robot", "check"]
    commands = {"p3d robot check robot.urdf": p3d + [str(urdf)],
                "p3d robot check robot.xml": p3d + [str(mjcf)]}
    try:
        import mujoco  # noqa: F401

        commands["mujoco compile robot.xml"] = [sys.executable, "-c",
                                                f"import mujoco; mujoco.MjModel.from_xml_path({str(mjcf)!r})"]
    except ImportError:
        print("mujoco is not installed: its column is left out")
    found: dict[str, list[tuple[float, float]]] = {name: [] for name in commands}
    load = os.getloadavg()
    for _ in range(runs):  # alternate, so that a burst of load hits every command alike
        for name, command in commands.items():
            found[name].append(timed(command))
    print(f"{LINKS}-link robot of primitives, {runs} runs each, load average before {load[0]:.2f} "
          f"and after {os.getloadavg()[0]:.2f} ({os.cpu_count()} cores)")
    base = None
    for name, times in found.items():
        wall = statistics.median(t[0] for t in times)
        cpu = statistics.median(t[1] for t in times)
        base = base or (wall, cpu)
        print(f"  {name:32s} wall {wall * 1e3:7.1f} ms  cpu {cpu * 1e3:7.1f} ms  "
              f"(x{wall / base[0]:.2f} wall, x{cpu / base[1]:.2f} cpu of the first)")


if __name__ == "__main__":
    main()
