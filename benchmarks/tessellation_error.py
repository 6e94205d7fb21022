"""How far the tessellated stand-ins (``--tessellate N``) are from the exact round shapes.

For the sphere (latitude-longitude, N segments around and N/2 stacks) and the cylinder
(inscribed N-gon prism), prints the relative error of the volume and of the largest principal
moment of inertia against the closed forms, and the error times N² (which settles to a
constant: the error is O(1/N²)). The table in docs/shapes.md is this script's output:

    python benchmarks/tessellation_error.py            # Markdown table
"""

from __future__ import annotations

import numpy as np

from p3d_cli.geometry.inertia import inertia_from_second_moments
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.shapes import Cylinder, Sphere

SEGMENTS = (8, 16, 32, 64, 128, 256, 512, 1024)


def errors(shape, n: int) -> tuple[int, float, float]:
    """Triangle count, relative volume error, relative error of the largest principal moment."""
    exact = shape.moments()
    tris = shape.tessellate(n)
    approx = triangle_moments(tris)
    ev = (approx.volume - exact.volume) / exact.volume
    ie = np.linalg.eigvalsh(inertia_from_second_moments(exact.central))[-1]
    ia = np.linalg.eigvalsh(inertia_from_second_moments(approx.central))[-1]
    return len(tris), ev, (ia - ie) / ie


def main() -> None:
    print("| shape | N | triangles | volume error | volume error × N² | inertia error (largest principal) |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, shape in (("sphere", Sphere(1.0)), ("cylinder", Cylinder(1.0, 1.0))):
        for n in SEGMENTS:
            count, ev, ei = errors(shape, n)
            print(f"| {label} | {n} | {count} | {ev:.3e} | {ev * n * n:.3f} | {ei:.3e} |")


if __name__ == "__main__":
    main()
