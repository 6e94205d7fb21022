#!/usr/bin/env python
"""Whole-process timings of ``p3d props`` against trimesh, meshio and numpy-stl.

What it does:

1. Generates closed test meshes (a grid torus, so every edge is shared by two faces in opposite
   directions) of 10k, 100k and 1M triangles as binary STL, ASCII STL, OBJ and binary PLY
   (OBJ and PLY with shared vertices), 4M triangles as binary STL (``--huge-formats``), plus
   a 400-triangle ``tiny.stl``, in a work directory outside the repository (default: a fresh
   temporary directory; ``--workdir`` keeps them for the next run).
2. Runs each tool as a separate process, the way a shell loop or CI job would, alternating the
   tools run by run (and rotating which goes first), and reads each child's wall time, user+sys
   CPU time and peak resident memory (``ru_maxrss``) from ``os.wait4``. The same numbers can
   be had by hand with ``/usr/bin/time -v``. Runs per tool: ``--runs`` (5) up to 100k
   triangles, ``--runs-large`` (3) at 1M, ``--runs-huge`` (2) at 4M; numpy-stl 2 from 100k.
   One untimed warm-up run of every tool fills the page and bytecode caches first.
3. Checks that every tool printed the same volume (so none skipped the work), and prints a
   markdown table of medians and of each peer's time relative to p3d; the table is also
   written to ``--output``.

Peers (each a whole ``python`` process, so the import cost is part of the figure, as it is
for a user):

- trimesh: ``trimesh.load(path)`` then ``mesh.mass_properties``;
- meshio: ``meshio.read(path)`` then the same tetrahedron sums as p3d, in plain numpy;
- numpy-stl (STL only): ``stl.mesh.Mesh.from_file(path).get_mass_properties()``. It takes
  ~30 s per million triangles, so by default it runs only up to 100k triangles
  (``--numpy-stl-max``);
- the streaming numpy floor, ``benchmarks/floor.py`` (binary STL, binary PLY, ASCII STL): read
  in blocks, integrate, accumulate, no checks; the least a numpy tool does (issue 32);
- admesh (STL only, from the system's packages; up to ``--admesh-max`` triangles).

Usage::

    python benchmarks/bench_props.py                 # the full table, a few minutes
    python benchmarks/bench_props.py --quick         # 10k and 100k only, under a minute
    python benchmarks/bench_props.py --runs 7 --workdir /tmp/p3d-bench --output table.md
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from installed import cache_bytecode

#: Triangle counts and the torus grid (u, v) giving 2·u·v triangles.
SIZES = {10_000: (100, 50), 100_000: (250, 200), 1_000_000: (1000, 500), 4_000_000: (2000, 1000)}
TINY = (20, 10)
FORMATS = ("stl-binary", "stl-ascii", "obj", "ply-binary")
EXTENSIONS = {"stl-binary": "stl", "stl-ascii": "stl", "obj": "obj", "ply-binary": "ply"}

TRIMESH = ("import sys, trimesh\n"
           "m = trimesh.load(sys.argv[1])\n"
           "print(repr(float(m.mass_properties['volume'])))\n")

NUMPY_STL = ("import sys\n"
             "from stl import mesh\n"
             "volume, cog, inertia = mesh.Mesh.from_file(sys.argv[1]).get_mass_properties()\n"
             "print(repr(float(volume)))\n")

# meshio reads the file; the integral is the same signed-tetrahedron sum p3d uses (volume,
# centre, inertia about the centre), written plainly in numpy about the bounding-box centre.
MESHIO = ("import sys, meshio, numpy as np\n"
          "m = meshio.read(sys.argv[1])\n"
          "faces = np.concatenate([c.data for c in m.cells if c.type == 'triangle'])\n"
          "p = np.asarray(m.points, dtype=np.float64)\n"
          "o = 0.5 * (p.min(axis=0) + p.max(axis=0))\n"
          "a, b, c = (p[faces[:, k]] - o for k in range(3))\n"
          "d = np.einsum('ij,ij->i', a, np.cross(b, c))\n"
          "s = a + b + c\n"
          "volume = d.sum() / 6\n"
          "center = (d[:, None] * s).sum(axis=0) / 24 / volume\n"
          "q = (np.einsum('n,ni,nj->ij', d, a, a) + np.einsum('n,ni,nj->ij', d, b, b)\n"
          "     + np.einsum('n,ni,nj->ij', d, c, c) + np.einsum('n,ni,nj->ij', d, s, s)) / 120\n"
          "second = q - volume * np.outer(center, center)\n"
          "inertia = np.trace(second) * np.eye(3) - second\n"
          "print(repr(float(volume)))\n")


# --- meshes ------------------------------------------------------------------------------

def torus(u: int, v: int, major: float = 3.0, minor: float = 1.0):
    """A closed grid torus: ``(u·v, 3)`` float64 vertices and ``(2·u·v, 3)`` int64 faces,
    wound outward. Placed off the origin, as real parts are."""
    import numpy as np
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = major + minor * np.cos(phi)
    vertices = np.stack([ring * np.cos(theta), ring * np.sin(theta), minor * np.sin(phi)], axis=-1)
    vertices = vertices.reshape(-1, 3) + np.array([12.5, -7.25, 3.0])
    # Round to float32 so that every format stores the same coordinates.
    vertices = vertices.astype(np.float32).astype(np.float64)
    a = (i * v + j).reshape(-1)
    b = (((i + 1) % u) * v + j).reshape(-1)
    c = (((i + 1) % u) * v + (j + 1) % v).reshape(-1)
    d = (i * v + (j + 1) % v).reshape(-1)
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return vertices, faces


def write_stl_binary(path, vertices, faces):
    import numpy as np
    record = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    out = np.zeros(len(faces), record)
    out["corners"] = vertices[faces]
    with open(path, "wb") as f:
        f.write(b"p3d benchmark torus".ljust(80, b" "))
        f.write(np.uint32(len(faces)).tobytes())
        out.tofile(f)


def write_stl_ascii(path, vertices, faces):
    # Each vertex is formatted once; the file repeats the same text at every corner, so shared
    # corners parse to identical numbers (the mesh stays closed).
    import numpy as np
    text = np.array([f"      vertex {x:.8e} {y:.8e} {z:.8e}\n" for x, y, z in vertices.tolist()],
                    dtype=object)
    corners = text[faces]
    head = "  facet normal 0 0 0\n    outer loop\n"
    tail = "    endloop\n  endfacet\n"
    with open(path, "w") as f:
        f.write("solid torus\n")
        step = 1 << 16
        for start in range(0, len(faces), step):
            block = corners[start:start + step]
            f.write("".join(head + a + b + c + tail for a, b, c in block.tolist()))
        f.write("endsolid torus\n")


def write_obj(path, vertices, faces):
    with open(path, "w") as f:
        f.write("# p3d benchmark torus\n")
        f.write("".join(f"v {x:.8g} {y:.8g} {z:.8g}\n" for x, y, z in vertices.tolist()))
        f.write("".join(f"f {a} {b} {c}\n" for a, b, c in (faces + 1).tolist()))


def write_ply_binary(path, vertices, faces):
    import numpy as np
    header = ("ply\nformat binary_little_endian 1.0\ncomment p3d benchmark torus\n"
              f"element vertex {len(vertices)}\nproperty float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    record = np.dtype([("n", "u1"), ("v", "<i4", (3,))])
    out = np.empty(len(faces), record)
    out["n"] = 3
    out["v"] = faces
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        vertices.astype("<f4").tofile(f)
        out.tofile(f)


WRITERS = {"stl-binary": write_stl_binary, "stl-ascii": write_stl_ascii, "obj": write_obj,
           "ply-binary": write_ply_binary}


def mesh_path(workdir: str, fmt: str, size: int) -> str:
    return os.path.join(workdir, f"torus-{size}-{fmt}.{EXTENSIONS[fmt]}")


def generate(workdir: str, sizes, formats, log) -> None:
    """Write every (size, format) file that is not there yet, and ``tiny.stl``.

    Runs in a child process (``--generate``): the timing parent must stay small, because a
    child's peak RSS as the kernel reports it (``ru_maxrss``) starts from the memory of the
    process that forked it.
    """
    wanted = [(TINY, os.path.join(workdir, "tiny.stl"), "stl-binary")]
    wanted += [(SIZES[s], mesh_path(workdir, f, s), f) for s in sizes for f in formats]
    for grid, path, fmt in wanted:
        if os.path.exists(path):
            continue
        t = time.perf_counter()
        vertices, faces = torus(*grid)
        WRITERS[fmt](path + ".part", vertices, faces)
        os.replace(path + ".part", path)
        log(f"  wrote {os.path.basename(path)} ({os.path.getsize(path) / 1e6:.1f} MB, "
            f"{time.perf_counter() - t:.1f} s)")


# --- timing ------------------------------------------------------------------------------

@dataclass
class Runs:
    wall: list = field(default_factory=list)
    cpu: list = field(default_factory=list)
    rss_mb: list = field(default_factory=list)
    volume: float | None = None
    error: str = ""

    def median(self, what: str) -> float:
        return statistics.median(getattr(self, what))


def child_env(workdir: str) -> dict:
    """The environment of every timed process: bytecode cached, as for an installed package
    (``installed.cache_bytecode``), in the work directory, for every tool alike."""
    return cache_bytecode(os.path.join(workdir, "pycache"))


ENV: dict | None = None
ADMESH: str | None = None


def run_once(argv, log_dir: str) -> tuple[float, float, float, str]:
    """Run ``argv`` as a child; return wall s, user+sys s, peak RSS MB, stdout."""
    out_path = os.path.join(log_dir, "stdout.txt")
    err_path = os.path.join(log_dir, "stderr.txt")
    with open(out_path, "wb") as out, open(err_path, "wb") as err:
        start = time.perf_counter()
        child = subprocess.Popen(argv, stdout=out, stderr=err, stdin=subprocess.DEVNULL, env=ENV)
        _, status, usage = os.wait4(child.pid, 0)
        wall = time.perf_counter() - start
        child.returncode = os.waitstatus_to_exitcode(status)
    with open(out_path) as f:
        stdout = f.read()
    if child.returncode != 0:
        with open(err_path) as f:
            raise RuntimeError(f"{' '.join(argv)} exited {child.returncode}: {f.read()[-2000:]}")
    # ru_maxrss is in kilobytes on Linux (bytes on macOS).
    rss = usage.ru_maxrss / (1 << 20 if sys.platform == "darwin" else 1 << 10)
    return wall, usage.ru_utime + usage.ru_stime, rss, stdout


FLOOR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "floor.py")
#: Formats the numpy floor (floor.py) reads, and admesh (STL only).
FLOOR_FORMATS = ("stl-binary", "stl-ascii", "ply-binary")


def admesh_volume(stdout: str) -> None:
    """admesh prints its float32 volume (about 1e-4 off): read nothing, check nothing."""
    if "Number of facets" not in stdout:
        raise RuntimeError("admesh printed no results")


def p3d_volume(stdout: str) -> float:
    return float(json.loads(stdout)["volume"])


def peer_volume(stdout: str) -> float:
    return float(stdout.strip().splitlines()[-1])


def time_tools(tools: dict, runs: int, log_dir: str) -> dict[str, Runs]:
    """Alternate the tools run by run, rotating which goes first; return their runs.

    ``tools``: name -> (argv, parse stdout to a volume[, fewer runs for this tool]).
    """
    results = {name: Runs() for name in tools}
    names = list(tools)
    for r in range(runs):
        shift = r % len(names)
        for name in names[shift:] + names[:shift]:
            argv, parse, *limit = tools[name]
            got = results[name]
            if got.error or (limit and r >= limit[0]):
                continue
            try:
                wall, cpu, rss, stdout = run_once(argv, log_dir)
            except RuntimeError as exc:        # a tool that cannot read the file: say so
                got.error = str(exc).strip().splitlines()[-1][:200]
                print(f"  {name} failed: {got.error}", file=sys.stderr)
                continue
            got.wall.append(wall)
            got.cpu.append(cpu)
            got.rss_mb.append(rss)
            got.volume = parse(stdout)
    return results


def warm(path: str) -> None:
    """Read the file once so that every tool finds it in the page cache."""
    with open(path, "rb") as f:
        while f.read(1 << 24):
            pass


# --- the table ---------------------------------------------------------------------------

def fmt_s(x: float) -> str:
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def machine() -> str:
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    ram = ""
    try:
        ram = f", {os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES') / 2**30:.0f} GiB RAM"
    except (ValueError, OSError):
        pass
    return f"{cpu}, {os.cpu_count()} logical CPUs{ram}, {platform.system()} {platform.release()}"


def versions() -> str:
    # From the package metadata: importing the packages here would grow this process, whose
    # memory every child's reported peak RSS starts from.
    from importlib.metadata import PackageNotFoundError, version
    parts = [f"Python {platform.python_version()}"]
    for name in ("numpy", "trimesh", "meshio", "numpy-stl", "p3d_cli"):
        try:
            parts.append(f"{name.replace('_cli', '')} {version(name)}")
        except PackageNotFoundError:
            parts.append(f"{name} not installed")
    return ", ".join(parts)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--workdir", help="where the meshes go (kept); default a temporary directory")
    parser.add_argument("--runs", type=int, default=5, help="runs per tool up to 100k triangles (default 5)")
    parser.add_argument("--runs-large", type=int, default=3, help="runs per tool at 1M triangles (default 3)")
    parser.add_argument("--runs-huge", type=int, default=2, help="runs per tool at 4M triangles (default 2)")
    parser.add_argument("--quick", action="store_true", help="10k and 100k triangles only, 3 runs")
    parser.add_argument("--sizes", help="comma-separated triangle counts (default 10000,100000,1000000,4000000)")
    parser.add_argument("--formats", default=",".join(FORMATS),
                        help=f"comma-separated formats to time (default {','.join(FORMATS)})")
    parser.add_argument("--huge-formats", default="stl-binary",
                        help="formats generated and timed at 4M triangles (default stl-binary)")
    parser.add_argument("--numpy-stl-max", type=int, default=100_000,
                        help="largest size numpy-stl is timed at (default 100000: it takes ~30 s per 1M)")
    parser.add_argument("--admesh-max", type=int, default=1_000_000,
                        help="largest size admesh is timed at (default 1000000; its edge hash table is slower "
                        "than linear beyond)")
    parser.add_argument("--output", default=None, help="also write the markdown table here "
                        "(default bench_props.md in the work directory)")
    parser.add_argument("--generate", nargs=3, metavar=("WORKDIR", "SIZES", "FORMATS"), help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    command_line = " ".join(sys.argv[1:] if argv is None else argv)
    if args.generate:
        workdir, sizes, formats = args.generate
        generate(workdir, [int(x) for x in sizes.split(",")], formats.split(","),
                 lambda text: print(text, file=sys.stderr, flush=True))
        return 0

    if args.quick:
        sizes = [10_000, 100_000]
        args.runs = min(args.runs, 2)
        args.numpy_stl_max = min(args.numpy_stl_max, 10_000)
    elif args.sizes:
        sizes = [int(s) for s in args.sizes.split(",")]
    else:
        sizes = sorted(SIZES)
    unknown = set(sizes) - set(SIZES)
    if unknown:
        parser.error(f"sizes must be among {sorted(SIZES)}")
    formats = [f for f in args.formats.split(",") if f]
    huge_formats = [f for f in args.huge_formats.split(",") if f and f in formats]
    if set(formats) - set(FORMATS):
        parser.error(f"formats must be among {', '.join(FORMATS)}")

    def log(text: str) -> None:
        print(text, file=sys.stderr, flush=True)

    workdir = args.workdir or tempfile.mkdtemp(prefix="p3d-bench-")
    os.makedirs(workdir, exist_ok=True)
    log(f"meshes in {workdir}")
    python = sys.executable
    p3d = shutil.which("p3d", path=os.path.dirname(python)) or shutil.which("p3d")
    if p3d is None:
        parser.error("no p3d command found next to this python or on PATH")
    t_all = time.perf_counter()
    for size in sizes:
        wanted = huge_formats if size >= 4_000_000 else formats
        if wanted:
            subprocess.run([python, os.path.abspath(__file__), "--generate", workdir, str(size), ",".join(wanted)],
                           check=True)

    global ENV, ADMESH
    ENV = child_env(workdir)
    ENV.pop("P3D_PURE_NUMPY", None)
    ADMESH = shutil.which("admesh")
    if ADMESH is None:
        log("admesh not found: its column is left empty")
    log_dir = tempfile.mkdtemp(prefix="p3d-bench-out-")
    tiny = os.path.join(workdir, "tiny.stl")
    # Warm-up, untimed: fills the bytecode cache of every tool and the page cache.
    log("warm-up")
    subprocess.run([python, os.path.abspath(__file__), "--generate", workdir, "10000", ",".join(FORMATS)], check=True)
    for path in [tiny] + [mesh_path(workdir, f, 10_000) for f in FORMATS]:
        commands = [[p3d, "props", path, "--json"], [python, "-c", TRIMESH, path], [python, "-c", MESHIO, path]]
        if path.endswith(".stl"):
            commands.append([python, "-c", NUMPY_STL, path])
        for argv in commands:
            try:
                run_once(argv, log_dir)
            except RuntimeError:
                pass                          # reported when timed

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = []
    lines.append(f"Whole-process medians, {time.strftime('%Y-%m-%d %H:%M %Z')}; {machine()}; "
                 f"load average {load:.1f} at the start. Command: `python benchmarks/bench_props.py "
                 f"{command_line}`.")
    lines.append(f"{versions()}.")
    lines.append("")

    # Start-up: a tiny file through p3d versus importing trimesh alone.
    startup_runs = 2 * args.runs
    log(f"start-up ({startup_runs} runs each)")
    start = time_tools({
        "p3d": ([p3d, "props", tiny, "--json"], p3d_volume),
        "import trimesh": ([python, "-c", "import trimesh"], lambda s: None),
        "python": ([python, "-c", "pass"], lambda s: None),
    }, startup_runs, log_dir)
    p3d_start = start["p3d"].median("wall")
    p3d_start_cpu = start["p3d"].median("cpu")
    lines.append("**Start-up**: `p3d props tiny.stl --json` (400 triangles) against `python -c \"import "
                 "trimesh\"` alone and an empty `python -c pass`.")
    lines.append("")
    lines.append("| command | runs | wall s | user+sys s | peak RSS MB |")
    lines.append("|---|---:|---:|---:|---:|")
    for name, label in (("p3d", "`p3d props tiny.stl --json`"), ("import trimesh", "`python -c \"import trimesh\"`"),
                        ("python", "`python -c pass`")):
        r = start[name]
        lines.append(f"| {label} | {startup_runs} | {fmt_s(r.median('wall'))} | {fmt_s(r.median('cpu'))} "
                     f"| {r.median('rss_mb'):.0f} |")
    lines.append("")
    lines.append(f"`p3d props` on a tiny file is {start['import trimesh'].median('wall') / p3d_start:.1f}× faster "
                 f"than `import trimesh` alone (wall; {start['import trimesh'].median('cpu') / p3d_start_cpu:.1f}× "
                 "in CPU time).")
    lines.append("")

    # The size sweep.
    lines.append("**Size sweep.** Medians over *runs* whole processes per tool, alternated. Times in "
                 "seconds, wall clock unless marked cpu (user+sys, which other load on the machine "
                 "disturbs less); *×trimesh* = trimesh's time / p3d's; *×fastest* = the fastest peer's "
                 "wall time / p3d's; *floor* = benchmarks/floor.py, a numpy program that only reads the "
                 "file in blocks and integrates (no checks: the least a numpy tool does), and *p3d / floor* "
                 "p3d's CPU time over it; *admesh* = `admesh FILE` (STL, up to `--admesh-max` triangles); "
                 "*ns/tri* = p3d's marginal CPU time per triangle, from the next "
                 "smaller size of the same format: flat when the cost grows linearly (noisy at "
                 "100k, where it is a small difference of two start-up-dominated runs); RSS = peak "
                 "resident memory.")
    lines.append("")
    lines.append("| format | triangles | file MB | runs | p3d | trimesh | meshio | numpy-stl | ×trimesh "
                 "| ×fastest | p3d cpu | trimesh cpu | ×trimesh cpu | floor cpu | p3d / floor cpu | admesh cpu "
                 "| ns/tri | p3d RSS MB | trimesh RSS MB |")
    lines.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    memory_rows, failures = [], []
    previous: dict[str, tuple[int, float]] = {}
    for fmt in formats:
        for size in sizes:
            if size >= 4_000_000 and fmt not in huge_formats:
                continue
            path = mesh_path(workdir, fmt, size)
            warm(path)
            runs = args.runs if size <= 100_000 else args.runs_large if size <= 1_000_000 else args.runs_huge
            tools = {"p3d": ([p3d, "props", path, "--json"], p3d_volume),
                     "trimesh": ([python, "-c", TRIMESH, path], peer_volume),
                     "meshio": ([python, "-c", MESHIO, path], peer_volume)}
            if fmt in FLOOR_FORMATS:
                tools["floor"] = ([python, FLOOR, path], peer_volume)
            if fmt.startswith("stl") and size <= args.admesh_max and ADMESH:
                tools["admesh"] = ([ADMESH, path], admesh_volume)
            if fmt.startswith("stl") and size <= args.numpy_stl_max:
                # numpy-stl takes seconds from 100k triangles up: two runs there.
                tools["numpy-stl"] = ([python, "-c", NUMPY_STL, path], peer_volume,
                                      runs if size < 100_000 else min(runs, 2))
            log(f"{fmt} {size}: {', '.join(tools)} × {runs}")
            got = time_tools(tools, runs, log_dir)
            ok = {name: r for name, r in got.items() if not r.error}
            failures += [f"{name} on {fmt} {size:,}: {r.error}" for name, r in got.items() if r.error]
            reference = ok["p3d"].volume if "p3d" in ok else None
            for name, r in ok.items():
                # Every tool must find the same volume, or the timing may be of skipped work
                # (admesh's float32 volume is not checked).
                if reference is not None and r.volume is not None and abs(r.volume - reference) > 1e-6 * abs(reference):
                    raise RuntimeError(f"{name} on {path}: volume {r.volume} differs from p3d's {reference}")

            def cell(name, what="wall"):
                if name not in got:
                    return "–"
                return "failed" if got[name].error else fmt_s(got[name].median(what))

            peers = [r for name, r in ok.items() if name not in ("p3d", "floor")]
            mb = os.path.getsize(path) / 1e6
            x_trimesh = x_trimesh_cpu = "–"
            if "p3d" in ok and peers:
                p3d_s, p3d_cpu = ok["p3d"].median("wall"), ok["p3d"].median("cpu")
                x_wall = f"{min(r.median('wall') for r in peers) / p3d_s:.1f}×"
                if "trimesh" in ok:
                    x_trimesh = f"{ok['trimesh'].median('wall') / p3d_s:.1f}×"
                    x_trimesh_cpu = f"{ok['trimesh'].median('cpu') / p3d_cpu:.1f}×"
                # Marginal cost: CPU time added per triangle since the next smaller size of
                # this format, measured in the same stretch of the run; flat when linear.
                if fmt in previous:
                    prev_size, prev_cpu = previous[fmt]
                    ns = f"{(p3d_cpu - prev_cpu) / (size - prev_size) * 1e9:.0f}"
                else:
                    ns = "–"
                previous[fmt] = (size, p3d_cpu)
            else:
                x_wall = ns = "–"
            rss = {name: f"{r.median('rss_mb'):.0f}" if name in ok else "–" for name, r in got.items()}
            x_floor = (f"{ok['p3d'].median('cpu') / ok['floor'].median('cpu'):.2f}×"
                       if "p3d" in ok and "floor" in ok else "–")
            lines.append(f"| {fmt} | {size:,} | {mb:.1f} | {runs} | {cell('p3d')} | {cell('trimesh')} "
                         f"| {cell('meshio')} | {cell('numpy-stl')} | {x_trimesh} | {x_wall} | {cell('p3d', 'cpu')} "
                         f"| {cell('trimesh', 'cpu')} | {x_trimesh_cpu} | {cell('floor', 'cpu')} | {x_floor} "
                         f"| {cell('admesh', 'cpu')} | {ns} | {rss['p3d']} | {rss['trimesh']} |")
            if "p3d" in ok and (size >= 4_000_000 or (size == max(sizes) and fmt == "stl-binary")):
                memory_rows.append((fmt, size, mb, ok["p3d"].median("rss_mb")))
    lines.append("")
    for fmt, size, mb, rss in memory_rows:
        lines.append(f"**Peak memory**, {fmt}, {size:,} triangles: p3d {rss:.0f} MB for a file of "
                     f"{mb:.0f} MB ({rss / mb:.2f}× the file).")
    if args.numpy_stl_max < max(sizes):
        lines.append("")
        lines.append(f"numpy-stl is timed up to {args.numpy_stl_max:,} triangles only (about 30 s per "
                     "million triangles; `--numpy-stl-max` to change).")
    for text in failures:
        lines.append("")
        lines.append(f"Failed: {text}")
    lines.append("")
    lines.append(f"Benchmark wall time {time.perf_counter() - t_all:.0f} s (mesh generation included); "
                 f"load average {os.getloadavg()[0]:.1f} at the end.")

    table = "\n".join(lines) + "\n"
    sys.stdout.write(table)
    output = args.output or os.path.join(workdir, "bench_props.md")
    with open(output, "w") as f:
        f.write(table)
    log(f"table written to {output}")
    shutil.rmtree(log_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
