#!/usr/bin/env python
"""Whole-process timings of ``p3d props`` on glTF (GLB), 3MF and COLLADA against trimesh.

What it does:

1. Writes a closed grid torus of about 100k triangles (``--triangles``), placed by a node
   transform (scaled by 0.001 and turned), as GLB, 3MF and DAE with trimesh's exporters, and
   a tiny STL, in a temporary directory (``--workdir`` keeps them).
2. Runs each tool as a separate process, alternating which goes first, and reads each child's
   wall time and user+sys CPU time from ``os.wait4`` (the same numbers as ``/usr/bin/time``):

   - p3d: ``p3d props FILE --field volume --output-units U`` in the file's own unit U, as
     trimesh answers (GLB and 3MF read by p3d's own readers, DAE by trimesh's loader; then
     p3d's checks and exact integrals);
   - trimesh: ``trimesh.load(FILE, force="mesh")`` (the scene's meshes, placed, as one mesh)
     then ``mesh.mass_properties``.

3. Checks that both printed the same volume, and prints medians and the ratio p3d / trimesh,
   with the machine's load average before and after (the machine may be shared: compare the
   CPU columns when the load is high). The tiny STL row shows the start-up of STL runs, which
   import none of the scene readers.

Usage::

    python benchmarks/bench_formats.py              # 100k triangles, 5 runs per tool
    python benchmarks/bench_formats.py --runs 9 --triangles 200000
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
from installed import cache_bytecode

TRIMESH = ("import sys, trimesh\n"
           "m = trimesh.load(sys.argv[1], force='mesh')\n"
           "print(repr(float(m.mass_properties['volume'])))\n")


def torus(triangles: int):
    """A closed grid torus of about ``triangles`` faces (u·v·2), off the origin."""
    import numpy as np

    v = max(3, int((triangles / 2 / 1.25) ** 0.5))
    u = max(3, triangles // (2 * v))
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = 3.0 + np.cos(phi)
    vertices = np.stack([ring * np.cos(theta), ring * np.sin(theta), np.sin(phi)], axis=-1).reshape(-1, 3)
    vertices = (vertices + [12.5, -7.25, 3.0]).astype(np.float32).astype(np.float64)
    a = (i * v + j).reshape(-1)
    b = (((i + 1) % u) * v + j).reshape(-1)
    c = (((i + 1) % u) * v + (j + 1) % v).reshape(-1)
    d = (i * v + (j + 1) % v).reshape(-1)
    return vertices, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def write_files(workdir: str, triangles: int) -> dict[str, str]:
    import numpy as np
    import trimesh

    vertices, faces = torus(triangles)
    mesh = trimesh.Trimesh(vertices, faces, process=False)
    node = trimesh.transformations.rotation_matrix(0.4, [0, 0, 1]) @ np.diag([1e-3, 1e-3, 1e-3, 1.0])
    scene = trimesh.Scene()
    scene.add_geometry(mesh, node_name="torus", transform=node)
    paths = {}
    for ext in ("glb", "3mf"):
        paths[ext] = os.path.join(workdir, f"torus.{ext}")
        with open(paths[ext], "wb") as f:
            f.write(scene.export(file_type=ext))
    # trimesh's COLLADA exporter writes meshes without a scene graph: place the mesh itself.
    paths["dae"] = os.path.join(workdir, "torus.dae")
    placed = mesh.copy()
    placed.apply_transform(node)
    with open(paths["dae"], "wb") as f:
        f.write(placed.export(file_type="dae"))
    paths["stl (tiny)"] = os.path.join(workdir, "tiny.stl")
    trimesh.creation.box().export(paths["stl (tiny)"])
    return paths


def timed(command: list[str]) -> tuple[float, float, str]:
    """Wall and CPU (user + sys) seconds of one child process, and what it printed."""
    import time

    start = time.perf_counter()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    out = proc.stdout.read().decode()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed ({proc.returncode})")
    return wall, usage.ru_utime + usage.ru_stime, out.strip()


def main() -> None:
    cache_bytecode()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--triangles", type=int, default=100_000)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--workdir")
    parser.add_argument("--only", nargs="*", help="file kinds to time (glb, 3mf, dae, stl); default all")
    args = parser.parse_args()
    workdir = args.workdir or tempfile.mkdtemp(prefix="p3d-bench-formats-")
    os.makedirs(workdir, exist_ok=True)
    paths = write_files(workdir, args.triangles)
    p3d = [sys.executable, "-m", "p3d_cli", "props"]
    # trimesh answers in the file's own unit; p3d in SI unless told: ask for the file's unit.
    units = {".3mf": ["--output-units", "mm"], ".glb": ["--output-units", "m"], ".dae": ["--output-units", "m"]}
    tools = {"p3d": lambda path: p3d + [path, "--field", "volume"] + units.get(os.path.splitext(path)[1], []),
             "trimesh": lambda path: [sys.executable, "-c", TRIMESH, path]}
    load_before = os.getloadavg()
    print(f"{args.triangles} triangles, {args.runs} runs per tool, load average {load_before[0]:.2f}\n")
    print("| file | p3d wall s | trimesh wall s | wall ratio | p3d CPU s | trimesh CPU s | CPU ratio |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for name, path in paths.items():
        if args.only and name.split()[0] not in args.only:
            continue
        runs: dict[str, list[tuple[float, float]]] = {tool: [] for tool in tools}
        volumes = {}
        for tool, command in tools.items():   # untimed warm-up
            volumes[tool] = float(timed(command(path))[2].split()[-1])
        # pycollada (trimesh's COLLADA reader) parses the decimals as float32, p3d as float64.
        tolerance = 1e-6 if name == "dae" else 1e-9
        if abs(volumes["p3d"] - volumes["trimesh"]) > tolerance * abs(volumes["trimesh"]):
            raise SystemExit(f"{name}: the volumes differ: {volumes}")
        for run in range(args.runs):
            order = list(tools) if run % 2 == 0 else list(reversed(tools))
            for tool in order:
                wall, cpu, _ = timed(tools[tool](path))
                runs[tool].append((wall, cpu))
        med = {tool: (statistics.median(w for w, _ in r), statistics.median(c for _, c in r))
               for tool, r in runs.items()}
        print(f"| {name} | {med['p3d'][0]:.3f} | {med['trimesh'][0]:.3f} | {med['p3d'][0] / med['trimesh'][0]:.2f} "
              f"| {med['p3d'][1]:.3f} | {med['trimesh'][1]:.3f} | {med['p3d'][1] / med['trimesh'][1]:.2f} |")
    print(f"\nload average before {load_before[0]:.2f}, after {os.getloadavg()[0]:.2f} "
          f"({os.cpu_count()} cores); ratio < 1: p3d is faster")


if __name__ == "__main__":
    main()
