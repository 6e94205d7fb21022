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
The same inputs through ``--csv`` and ``--field`` (with an unreadable input among them, whose
row or empty line keeps its place), ``repair --json/--csv``, and small files written for the
case that make each warning code the readers and the measurements give (shown on stderr, in
the JSON and CSV records, silenced by ``--ignore-warning`` and thresholds, counted by
``--strict``).
Prints each case that differs and exits 1 if any does; nothing is stored between runs.
"""

from __future__ import annotations

import argparse
import os
import struct
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
CUBE_V = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
CUBE_F = ("f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\n"
          "f 4 1 5\nf 4 5 8\n")


def _far(vertex: str) -> list[float]:
    """A cube corner 100 km (in its unit) from the origin: float32 resolves it coarsely."""
    x, y, z = (float(c) for c in vertex.split()[1:])
    return [x + 1e5, y, z]


#: Small files that make each warning a reader or a measurement gives, by code.
WARNING_FILES = {
    "open.obj": CUBE_V + "\n".join(CUBE_F.splitlines()[2:]) + "\n",
    "inward.obj": CUBE_V + "".join("f " + " ".join(reversed(line.split()[1:])) + "\n" for line in CUBE_F.splitlines()),
    "flat.obj": "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 3 2\n",
    "skipped.obj": CUBE_V + "vt 0 0\nusemtl steel\nbogus 1 2\n1/617/894\n" + CUBE_F,
    "trailing.off": "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n9 9 9\n8 8 8\n",
    "trailing.ply": ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                     "element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                     "0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n7 7\n"),
    "noend.stl": ("solid t\nfacet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 1 0\nvertex 1 0 0\nendloop\nendfacet\n"
                  "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 0 1\nendloop\nendfacet\n"
                  "facet normal 0 0 0\nouter loop\nvertex 0 0 0\nvertex 0 0 1\nvertex 0 1 0\nendloop\nendfacet\n"
                  "facet normal 0 0 0\nouter loop\nvertex 1 0 0\nvertex 0 1 0\nvertex 0 0 1\nendloop\nendfacet\n"),
    "far.stl": b"".join([b"far float32 cube".ljust(80), struct.pack("<I", 12)] + [
        struct.pack("<12fH", 0, 0, 0, *(c for i in f.split()[1:] for c in _far(CUBE_V.splitlines()[int(i) - 1])), 0)
        for f in CUBE_F.splitlines()]),
}
WARNING_ASSEMBLY = """parts:
  - name: lid
    mesh: open.obj
  - name: body
    shape: box:1,1,1
    translate: [0, 0, 5]
"""


def cases() -> list[tuple]:
    """``(name, arguments)`` of every case, or ``(name, arguments, files)`` with files (text or
    bytes) to write first into the case's folder (``{out}`` in the arguments); other paths are relative to the repository."""
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
    out += output_cases(meshes)
    out.append(("render bracket", ["render", "sample_meshes/bracket.stl", "--output", "{out}/bracket.png"]))
    out.append(("render box svg", ["render", "box:1,2,3", "--svg", "--output", "{out}/box.svg"]))
    out.append(("render box json", ["render", "box:1,2,3", "--svg", "--output", "{out}/box.svg", "--json"]))
    return out


def output_cases(meshes: list[str]) -> list[tuple]:
    """``--csv`` and ``--field`` of the commands that have them, ``repair``, and the warnings."""
    out: list[tuple] = []
    some = meshes[:4] + ["no-such-file.stl"]
    fields = ["--field", "volume", "--field", "center_of_mass", "--field", "warning_codes", "--field", "bounds.min"]
    out.append(("props csv", ["props", *some, "--csv"]))
    out.append(("props csv precision", ["props", *some, "--csv", "--precision", "6"]))
    out.append(("props csv about", ["props", *some, "--csv", "--about", "1,2,3"]))
    out.append(("props fields", ["props", *some, *fields]))
    out.append(("props fields missing", ["props", *meshes[:1], "--field", "no_such_field"]))
    out.append(("props csv specs", ["props", *SPECS, "--csv", *PLACED]))
    out.append(("props fields specs", ["props", *SPECS, "--field", "mass", "--field", "inertia"]))
    out.append(("bounds csv", ["bounds", *some, "--csv"]))
    out.append(("bounds csv precision", ["bounds", *some, "--csv", "--precision", "4", *PLACED]))
    out.append(("bounds fields", ["bounds", *some, "--field", "min", "--field", "center.1", "--field", "warnings"]))
    out.append(("check csv", ["check", *some, "--csv"]))
    out.append(("check fields", ["check", *some, "--field", "ok", "--field", "failed", "--field", "volume"]))
    out.append(("both formats", ["props", meshes[0], "--csv", "--json"]))
    files = dict(WARNING_FILES, **{"assembly.yaml": WARNING_ASSEMBLY})
    warned = [f"{{out}}/{name}" for name in WARNING_FILES]
    for command in ("props", "bounds", "check"):
        out.append((f"{command} warnings text", [command, *warned], files))
        out.append((f"{command} warnings json", [command, *warned, "--json"], files))
        out.append((f"{command} warnings csv", [command, *warned, "--csv"], files))
    out.append(("props warnings fields", ["props", *warned, "--field", "warning_codes", "--field", "warnings"], files))
    out.append(("props warnings strict", ["props", *warned, "--strict"], files))
    out.append(("props warnings ignored", ["props", *warned, "--strict", "--ignore-warning", "open",
                                           "--ignore-warning", "skipped-lines", "--ignore-warning", "coarse-float32"],
                files))
    out.append(("props warnings threshold", ["props", "{out}/far.stl", "--strict", "--warning-threshold",
                                             "coarse-float32=1"], files))
    out.append(("props assembly warnings", ["props", "{out}/assembly.yaml", "--json"], files))
    out.append(("props assembly warnings csv", ["props", "{out}/assembly.yaml", "--csv"], files))
    out.append(("props assembly warnings text", ["props", "{out}/assembly.yaml"], files))
    out.append(("props montecarlo warnings", ["props", "box:1,1,0.001", "--rotate", "1,2,3:40", "--method",
                                              "montecarlo", "--samples", "2000", "--seed", "1", "--json"]))
    out.append(("props montecarlo open", ["props", "{out}/open.obj", "--method", "montecarlo", "--samples", "5000",
                                          "--seed", "2", "--json"], files))
    out.append(("props montecarlo inward", ["props", "{out}/inward.obj", "--method", "montecarlo", "--samples",
                                            "5000", "--seed", "2"], files))
    out.append(("props montecarlo cap", ["props", "box:1,1,1", "--method", "montecarlo", "--tolerance", "1e-9",
                                         "--seed", "2", "--json"]))
    out.append(("props unit slip", ["props", "box:50,40,5", "--density", "7850", "--json"]))
    out.append(("props unit slip text", ["props", "box:50,40,5", "--density", "7850"]))
    for style in ("--json", "--csv"):
        out.append((f"repair {style}", ["repair", "{out}/open.obj", "{out}/inward.obj", "no-such-file.stl",
                                        "--dry-run", style], files))
        out.append((f"repair {style} written", ["repair", "{out}/inward.obj", "-o", "{out}/fixed.obj", style], files))
    out.append(("repair text", ["repair", "{out}/open.obj", "{out}/inward.obj", "--dry-run"], files))
    return out


def run(tree: Path, arguments: list[str], inputs: dict[str, str] | None = None) -> tuple:
    """Exit status, stdout, stderr and the files written of ``p3d ARGUMENTS`` run from ``tree``
    (the p3d_cli imported is ``tree``'s: checked by ``main`` before any case runs)."""
    env = {**os.environ, "PYTHONPATH": str(tree), "PYTHONHASHSEED": "0", "COLUMNS": "100"}
    env.pop("P3D_DEBUG", None)
    with tempfile.TemporaryDirectory() as folder:
        args = [a.replace("{out}", folder) for a in arguments]
        for name, text in (inputs or {}).items():
            if isinstance(text, bytes):
                (Path(folder) / name).write_bytes(text)
            else:
                (Path(folder) / name).write_text(text)
        # Run from the tree itself: ``python -m`` puts the working folder first on sys.path, ahead
        # of PYTHONPATH, so from any other folder its p3d_cli (an editable install's own tree)
        # would answer for both sides. Inputs named relative to the repository are the same
        # files in either tree (sample_meshes/, examples/).
        done = subprocess.run([sys.executable, "-m", "p3d_cli", *args], cwd=tree, env=env,
                              capture_output=True, stdin=subprocess.DEVNULL)
        files = {p.name: p.read_bytes() for p in Path(folder).iterdir() if p.is_file() and p.name not in (inputs or {})}
    swap = lambda b: b.replace(folder.encode(), b"{out}")  # noqa: E731
    return done.returncode, swap(done.stdout), swap(done.stderr), files


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline", required=True, type=Path, help="the other source tree (a worktree)")
    parser.add_argument("--jobs", type=int, default=2)
    args = parser.parse_args()
    args.baseline = args.baseline.resolve()
    if not (args.baseline / "p3d_cli").is_dir():
        parser.error(f"{args.baseline} holds no p3d_cli")
    for tree in (HERE, args.baseline):
        probe = subprocess.run([sys.executable, "-c", "import p3d_cli; print(p3d_cli.__file__)"], cwd=tree,
                               env={**os.environ, "PYTHONPATH": str(tree)}, capture_output=True, text=True)
        if not Path(probe.stdout.strip()).resolve().is_relative_to(tree.resolve()):
            parser.error(f"run from {tree}, python imports p3d_cli from {probe.stdout.strip() or probe.stderr}")
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
