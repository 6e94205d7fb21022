"""Before/after: the same commands run by two source trees of p3d must print the same bytes.

Usage::

    git worktree add /tmp/p3d-before <commit>
    python benchmarks/same_outputs.py --baseline /tmp/p3d-before

For a change that moves code and should change no behaviour (a re-layout, a rename): every case
runs ``python -m p3d_cli ...`` with ``PYTHONPATH`` set to this tree, then to the baseline, and
their standard output, standard error, exit status and any file written are compared byte for
byte. Cases: ``--help`` of the group and of every command; ``props``, ``bounds`` and ``check``
``--json`` of every sample mesh, of shape specs (placed, with units, Monte Carlo) and of the
real meshes (``../shared/real-meshes/`` beside the repository, when present); ``solve --json``
of every example, at rest and stepped; ``robot check --json`` and ``robot fill`` of real robot
descriptions (``../shared/real-robots/``, when present); and ``render`` of a sample mesh.
Prints each case that differs and exits 1 if any does; nothing is stored between runs.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent
REAL_MESHES = HERE.parent / "shared" / "real-meshes"
REAL_ROBOTS = HERE.parent / "shared" / "real-robots"

COMMANDS = ("bounds", "check", "config", "diff", "props", "render", "robot", "solve")
SPECS = ("box:1,2,3", "sphere:0.5", "cylinder:1,2", "ellipsoid:1,2,3", "ecylinder:1,2,3", "wedge:1,2,3",
         "corner:1,2,3", "capsule:1,2")
ASSEMBLY = """units: mm
parts:
  - name: base
    mesh: {bracket}
    density: 2.7 g/cm^3
  - name: arm
    shape: box:10,20,30
    mass: 0.5 kg
    translate: [0, 0, 100]
    rotate: {{axis: z, degrees: 30}}
    scale: [1, -1, 1]
"""
PLACED = ("--scale", "2", "--rotate", "z:30", "--rotate", "x:10", "--translate", "1,2,3")


def cases() -> list[tuple]:
    """``(name, arguments)`` of every case, or ``(name, arguments, files)`` with files to write first
    into the case's folder (``{out}`` in the arguments); other paths are relative to the repository."""
    out: list[tuple] = [("help", ["--help"]), ("version", ["--version"])]
    out += [(f"{c} --help", [c, "--help"]) for c in COMMANDS]
    out += [(f"robot {c} --help", ["robot", c, "--help"]) for c in ("check", "fill")]
    meshes = sorted(str(p.relative_to(HERE)) for p in (HERE / "sample_meshes").iterdir()
                    if p.suffix.lower() in (".stl", ".obj", ".off", ".ply"))
    if REAL_MESHES.is_dir():
        meshes += sorted(str(p) for p in REAL_MESHES.iterdir() if p.suffix.lower() in (".stl", ".obj", ".off", ".ply"))
    for mesh in meshes:
        for command in ("props", "bounds", "check"):
            out.append((f"{command} {Path(mesh).name}", [command, mesh, "--json"]))
        out.append((f"props {Path(mesh).name} placed", ["props", mesh, "--json", *PLACED]))
    out.append(("props meshes table", ["props", *meshes[:3]]))
    out.append(("check meshes text", ["check", *meshes[:3]]))
    for spec in SPECS:
        out.append((f"props {spec}", ["props", spec, "--json"]))
        out.append((f"props {spec} placed", ["props", spec, "--json", *PLACED]))
        out.append((f"bounds {spec} placed", ["bounds", spec, "--json", *PLACED]))
        out.append((f"props {spec} units", ["props", spec, "--json", "--units", "mm", "--density", "7.85g/cm^3"]))
    out.append(("props montecarlo", ["props", "box:1,2,3", "--json", "--method", "montecarlo", "--samples", "20000",
                                     "--seed", "3"]))
    out.append(("props tessellate", ["props", "sphere:1", "--json", "--tessellate", "32"]))
    out.append(("props combine", ["props", "box:1,1,1", "sphere:1", "--combine", "--json"]))
    out.append(("props bad spec", ["props", "box:1,-2"]))
    out.append(("props missing", ["props", "no-such-file.stl"]))
    for scene in sorted((HERE / "examples").glob("*.yaml")):
        name = str(scene.relative_to(HERE))
        out.append((f"solve {scene.name}", ["solve", name, "--json"]))
        out.append((f"solve {scene.name} stepped", ["solve", name, "--json", "--steps", "200", "--dt", "0.001"]))
    kuka = REAL_ROBOTS / "kuka_kr16_2" / "kuka_kr16_support"
    if kuka.is_dir():
        paths = ["--package-path", f"kuka_kr16_support={kuka}"]
        out.append(("robot check kuka", ["robot", "check", str(kuka / "urdf" / "kr16_2.urdf"), "--json", *paths]))
        out.append(("robot fill kuka", ["robot", "fill", str(kuka / "urdf" / "kr16_2.urdf"), "--density", "2700",
                                        "--force", *paths]))
    vx300s = REAL_ROBOTS / "menagerie_vx300s" / "trossen_vx300s" / "vx300s.xml"
    if vx300s.is_file():
        out.append(("robot check vx300s", ["robot", "check", str(vx300s), "--json"]))
    soup = REAL_MESHES / "trimesh__soup.stl"
    if soup.is_file():
        out.append(("props soup shells", ["props", str(soup), "--json", "--shells"]))
        out.append(("check soup weld", ["check", str(soup), "--json", "--weld", "1e-6"]))
    assembly = ASSEMBLY.format(bracket=HERE / "sample_meshes" / "bracket.stl")
    for command in ("props", "bounds", "check"):
        out.append((f"{command} assembly", [command, "{out}/assembly.yaml", "--json"], {"assembly.yaml": assembly}))
    out.append(("render bracket", ["render", "sample_meshes/bracket.stl", "--output", "{out}/bracket.png"]))
    out.append(("render box svg", ["render", "box:1,2,3", "--svg", "--output", "{out}/box.svg"]))
    return out


#: ``python -m p3d_cli`` run from ``tree`` whatever the working folder (``sys.path[0]`` is it).
RUNNER = ("import runpy, sys; sys.path[0] = {tree!r}; "
          "runpy.run_module('p3d_cli', run_name='__main__', alter_sys=True)")


def run(tree: Path, arguments: list[str], inputs: dict[str, str] | None = None) -> tuple:
    """Exit status, stdout, stderr and the files written of ``p3d ARGUMENTS`` run from ``tree``."""
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONHASHSEED": "0", "COLUMNS": "100"}
    env.pop("P3D_DEBUG", None)
    with tempfile.TemporaryDirectory() as folder:
        args = [a.replace("{out}", folder) for a in arguments]
        for name, text in (inputs or {}).items():
            (Path(folder) / name).write_text(text)
        # Not ``python -m p3d_cli``: -m puts the working folder (this tree) first on the path, ahead
        # of PYTHONPATH, so the baseline run would import this tree too and every case would agree.
        done = subprocess.run([sys.executable, "-c", RUNNER.format(tree=str(tree)), *args], cwd=HERE, env=env,
                              capture_output=True, stdin=subprocess.DEVNULL)
        files = {p.name: p.read_bytes() for p in Path(folder).iterdir() if p.is_file() and p.name not in (inputs or {})}
    swap = lambda b: b.replace(folder.encode(), b"{out}")  # noqa: E731
    return done.returncode, swap(done.stdout), swap(done.stderr), files


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline", required=True, type=Path, help="the other source tree (a worktree)")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    if not (args.baseline / "p3d_cli").is_dir():
        parser.error(f"{args.baseline} holds no p3d_cli")
    todo = cases()

    def compare(case: tuple) -> str | None:
        name, arguments, *inputs = case
        ours, theirs = run(HERE, arguments, *inputs), run(args.baseline, arguments, *inputs)
        if ours == theirs:
            return None
        what = [k for k, a, b in zip(("status", "stdout", "stderr", "files"), ours, theirs) if a != b]
        return f"DIFFERS {name}: {', '.join(what)}"

    with ThreadPoolExecutor(args.jobs) as pool:
        found = list(pool.map(compare, todo))
    for line in found:
        if line:
            print(line)
    differing = sum(1 for line in found if line)
    print(f"{len(todo) - differing} of {len(todo)} cases print the same bytes; {differing} differ")
    return 1 if differing else 0


if __name__ == "__main__":
    sys.exit(main())
