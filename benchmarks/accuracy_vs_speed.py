"""Accuracy against speed for every way p3d can compute mass properties.

Measures, on this machine:

- the exact divergence-theorem method (float64, local origin) on an 82k-face ellipsoid mesh,
  against the exact rational oracle (tests/helpers/exact.py);
- Monte Carlo with 1e3 ... 1e6 samples on the same mesh, and 1e3 ... 1e7 on the analytic
  sphere (its inside test is cheap, so the 1e7 point stays within seconds), against the exact
  values, with the standard error each run states;
- tessellated spheres and cylinders at increasing segment counts N, against their closed forms
  (what a polyhedral approximation costs);
- float32 against float64 accumulation of the same divergence formulas.

Writes ``accuracy_vs_speed.md`` (a markdown table) and ``accuracy_vs_speed.png`` (error against
time, log-log) to the directory given on the command line (default ``benchmarks/out/``).

Usage::

    python benchmarks/accuracy_vs_speed.py [OUT_DIR]
"""

from __future__ import annotations

import datetime
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))

from helpers.exact import exact_moments  # noqa: E402

from p3d_cli.geometry.inertia import inertia_from_second_moments, mass_properties  # noqa: E402
from p3d_cli.measure.montecarlo import sample, triangles_inside  # noqa: E402
from p3d_cli.mesh.integrals import tetra_terms, triangle_moments  # noqa: E402
from p3d_cli.results import Bounds  # noqa: E402
from p3d_cli.shapes import Cylinder, Sphere  # noqa: E402


def machine() -> str:
    cpu = "unknown cpu"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{platform.machine()}, {cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}"


def best_time(fn, repeat=3):
    best, value = float("inf"), None
    for _ in range(repeat):
        start = time.perf_counter()
        value = fn()
        best = min(best, time.perf_counter() - start)
    return best, value


def errors(volume, inertia, ref_volume, ref_inertia):
    """Relative volume error and inertia error relative to the largest entry."""
    ev = abs(volume - ref_volume) / abs(ref_volume)
    ei = np.abs(inertia - ref_inertia).max() / np.abs(ref_inertia).max()
    return float(ev), float(ei)


def ellipsoid_mesh() -> np.ndarray:
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=6)          # 81,920 faces
    return np.asarray(mesh.triangles) * [1.0, 0.7, 0.4] + [3.0, -2.0, 1.0]


def accumulate(triangles: np.ndarray, dtype) -> tuple[float, np.ndarray]:
    """Volume and central inertia with every operation in ``dtype`` (about the bounding-box
    centre): what a float32 tool such as admesh does, against the same formulas in float64."""
    tri = np.asarray(triangles).astype(dtype)
    flat = tri.reshape(-1, 3)
    origin = ((flat.min(axis=0) + flat.max(axis=0)) / dtype(2)).astype(dtype)
    local = (tri - origin).transpose(1, 2, 0)
    terms = tetra_terms(local[0], local[1], local[2])[0].astype(dtype)
    total = terms.sum(axis=1, dtype=dtype)
    volume = total[0] / dtype(6)
    first = total[1:4] / dtype(24)
    second = np.empty((3, 3), dtype=dtype)
    for row, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
        second[i, j] = second[j, i] = total[4 + row] / dtype(120)
    c = first / volume
    central = second - volume * np.outer(c, c)
    return float(volume), inertia_from_second_moments(central.astype(np.float64))


def run(out: Path) -> list[dict]:
    rows: list[dict] = []

    def add(method, setting, seconds, ev, ei, stated=None, note=""):
        rows.append(dict(method=method, setting=setting, seconds=seconds, volume_error=ev,
                         inertia_error=ei, stated=stated, note=note))
        print(f"{method:28s} {setting:>12s} {seconds:9.4f} s  V {ev:.2e}  I {ei:.2e}"
              + ("" if stated is None else f"  stated {stated:.2e}"), flush=True)

    tri = ellipsoid_mesh()
    ref = exact_moments(tri)
    ref_v, ref_i = float(ref.volume), ref.inertia()

    seconds, m = best_time(lambda: triangle_moments(tri))
    p = mass_properties(m)
    ev, ei = errors(p.volume, p.inertia, ref_v, ref_i)
    add("exact (float64)", f"{len(tri)} faces", seconds, ev, ei, m.errors.volume / abs(m.volume),
        "vs rational oracle")

    for dtype, name in ((np.float64, "float64"), (np.float32, "float32")):
        seconds, (v, inertia) = best_time(lambda: accumulate(tri, dtype))
        add(f"accumulate in {name}", f"{len(tri)} faces", seconds, *errors(v, inertia, ref_v, ref_i))

    # Monte Carlo on the mesh (grid built once per run and included in the time).
    flat = tri.reshape(-1, 3)
    bounds = Bounds(flat.min(axis=0), flat.max(axis=0))
    for n in (10**3, 10**4, 10**5, 10**6):
        def mc():
            est = sample(triangles_inside(tri), bounds, n, seed=1)
            return est
        seconds, est = best_time(mc, repeat=1 if n >= 10**6 else 3)
        pm = mass_properties(est.moments())
        add("Monte Carlo, mesh", f"N={n:.0e}", seconds, *errors(pm.volume, pm.inertia, ref_v, ref_i),
            est.uncertainty()["volume"] / pm.volume)

    sphere = Sphere(1.0)
    sm = mass_properties(sphere.moments())
    for n in (10**3, 10**4, 10**5, 10**6, 10**7):
        seconds, est = best_time(lambda: sample(sphere.inside, sphere.bounds(), n, seed=2),
                                 repeat=1 if n >= 10**6 else 3)
        pm = mass_properties(est.moments())
        add("Monte Carlo, sphere", f"N={n:.0e}", seconds, *errors(pm.volume, pm.inertia, sm.volume, sm.inertia),
            est.uncertainty()["volume"] / pm.volume, "analytic inside test")

    for shape, label in ((Sphere(1.0), "tessellated sphere"), (Cylinder(1.0, 1.0), "tessellated cylinder")):
        closed = mass_properties(shape.moments())
        for n in (8, 16, 32, 64, 128, 256, 512, 1024):
            def tess():
                return mass_properties(triangle_moments(shape.tessellate(n)))
            seconds, pt = best_time(tess)
            add(label, f"N={n}", seconds, *errors(pt.volume, pt.inertia, closed.volume, closed.inertia),
                note=f"{len(shape.tessellate(n))} faces, vs closed form")
    return rows


def table(rows: list[dict], header: str) -> str:
    lines = [header, "",
             "| method | setting | time (s) | volume rel. error | inertia error (rel. to max) | stated (rel., volume) | note |",
             "|---|---|---:|---:|---:|---:|---|"]
    for r in rows:
        stated = "" if r["stated"] is None else f"{r['stated']:.1e}"
        lines.append(f"| {r['method']} | {r['setting']} | {r['seconds']:.4f} | {r['volume_error']:.1e} | "
                     f"{r['inertia_error']:.1e} | {stated} | {r['note']} |")
    return "\n".join(lines) + "\n"


def plot(rows: list[dict], path: Path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    floor = 1e-17     # a zero error is drawn at this floor
    fig, ax = plt.subplots(figsize=(7.5, 4.8), dpi=90)
    styles = {"exact (float64)": ("*", "k"), "accumulate in float64": ("s", "tab:gray"),
              "accumulate in float32": ("s", "tab:red"), "Monte Carlo, mesh": ("o", "tab:blue"),
              "Monte Carlo, sphere": ("o", "tab:cyan"), "tessellated sphere": ("^", "tab:green"),
              "tessellated cylinder": ("v", "tab:olive")}
    for method, (marker, color) in styles.items():
        group = [r for r in rows if r["method"] == method]
        if not group:
            continue
        t = [r["seconds"] for r in group]
        e = [max(r["volume_error"], floor) for r in group]
        ax.loglog(t, e, marker=marker, color=color, label=method, linestyle="-" if len(group) > 1 else "none")
        stated = [r["stated"] for r in group]
        if method.startswith("Monte Carlo"):
            ax.loglog(t, stated, color=color, linestyle=":", linewidth=1)
    ax.set_xlabel("time (s, best of 3; Monte Carlo ≥ 1e6 samples: one run)")
    ax.set_ylabel("relative volume error (|error|; 0 drawn at 1e-17)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(fontsize=7, loc="lower left")
    ax.text(0.99, 0.99, "dotted: Monte Carlo's stated standard error", transform=ax.transAxes,
            ha="right", va="top", fontsize=7)
    fig.tight_layout()
    fig.savefig(path)


def main(argv: list[str]) -> None:
    out = Path(argv[1]) if len(argv) > 1 else REPO / "benchmarks" / "out"
    out.mkdir(parents=True, exist_ok=True)
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    header = f"Measured {when} on {machine()}."
    rows = run(out)
    (out / "accuracy_vs_speed.md").write_text(table(rows, header))
    plot(rows, out / "accuracy_vs_speed.png", f"p3d accuracy vs speed ({when})")
    print(f"wrote {out / 'accuracy_vs_speed.md'} and {out / 'accuracy_vs_speed.png'}")


if __name__ == "__main__":
    main(sys.argv)
