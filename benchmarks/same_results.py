#!/usr/bin/env python
"""Byte-for-byte: the ``--json`` output of two source trees of p3d on the same files.

A speed change must not change any result. This runs ``p3d props FILE --json`` and
``p3d check FILE --json`` with one tree, then the other (``tree.py``), on the sample meshes,
on the real meshes of ``../shared/real-meshes`` (beside the repository, when present) and on
any further files named (the benchmark meshes), and compares exit status, standard output and
standard error byte for byte. With ``--pure-numpy`` the current tree also runs once more
with its compiled kernels switched off (``P3D_PURE_NUMPY=1``), which must give the same bytes.

Usage::

    git worktree add /tmp/p3d-main main          # or: git archive main | tar -x -C /tmp/p3d-main
    python benchmarks/same_results.py --baseline /tmp/p3d-main [--pure-numpy] [MESH ...]

Exit status 0 when every output is the same, 1 otherwise (each difference is listed).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent
TREE = Path(__file__).resolve().parent / "tree.py"
MESH_SUFFIXES = {".stl", ".obj", ".off", ".ply", ".glb", ".gltf", ".3mf", ".dae", ".amf", ".vtp", ".vtk"}


def inputs(extra: list[str]) -> list[Path]:
    """The sample meshes, the real meshes beside the repository, and ``extra``."""
    found = sorted(p for p in (HERE / "sample_meshes").iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    real = HERE.parent / "shared" / "real-meshes"
    if real.is_dir():
        found += sorted(p for p in real.iterdir() if p.suffix.lower() in MESH_SUFFIXES)
    return found + [Path(p) for p in extra]


def run(tree: Path, args: list[str], pure: bool = False) -> tuple[int, bytes, bytes]:
    """Exit status, stdout and stderr of ``p3d ARGS`` run from ``tree`` (``tree.py``: an editable
    install of either tree would otherwise answer for both)."""
    env = dict(os.environ)
    env.pop("P3D_PURE_NUMPY", None)
    if pure:
        env["P3D_PURE_NUMPY"] = "1"
    done = subprocess.run([sys.executable, str(TREE), str(tree), *args], env=env, capture_output=True,
                          stdin=subprocess.DEVNULL)
    return done.returncode, done.stdout, done.stderr


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, type=Path, help="source tree of the 'before' revision")
    parser.add_argument("--pure-numpy", action="store_true",
                        help="also compare this tree with its compiled kernels switched off")
    parser.add_argument("meshes", nargs="*", help="more mesh files (the benchmark meshes)")
    args = parser.parse_args(argv)
    baseline = args.baseline.resolve()
    differences = compared = 0
    for path in inputs(args.meshes):
        for command in (["props", str(path), "--json"], ["check", str(path), "--json"]):
            before = run(baseline, command)
            afters = [("now", run(HERE, command))]
            if args.pure_numpy:
                afters.append(("now, pure numpy", run(HERE, command, pure=True)))
            for label, after in afters:
                compared += 1
                if after != before:
                    differences += 1
                    print(f"DIFFERENT ({label}): p3d {' '.join(command)}: exit {before[0]} -> {after[0]}",
                          flush=True)
                    for name, a, b in (("stdout", before[1], after[1]), ("stderr", before[2], after[2])):
                        if a != b:
                            print(f"  {name} before: {a[:400]!r}\n  {name} after:  {b[:400]!r}")
            if all(after == before for _, after in afters):
                print(f"same: p3d {' '.join(command)}", flush=True)
    print(f"{compared} outputs compared, {differences} different")
    return 1 if differences else 0


if __name__ == "__main__":
    sys.exit(main())
