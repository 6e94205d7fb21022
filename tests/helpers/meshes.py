"""Small mesh builders: the unit cube's arrays, and STL files written from triangles."""

from __future__ import annotations

from pathlib import Path

import numpy as np

CUBE_VERTICES = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                          [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
CUBE_FACES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                       [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def cube_triangles() -> np.ndarray:
    """The unit cube [0, 1]³ as 12 outward-wound triangles, (12, 3, 3) float64."""
    return CUBE_VERTICES[CUBE_FACES]


def write_binary_stl(path, triangles: np.ndarray, header: bytes = b"p3d test") -> None:
    """Write ``triangles`` (n, 3, 3) as binary STL (float32, zero normals)."""
    triangles = np.asarray(triangles, dtype=np.float32)
    records = np.zeros(len(triangles), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = triangles
    with open(path, "wb") as f:
        f.write(header[:80].ljust(80, b" "))
        f.write(np.uint32(len(triangles)).tobytes())
        f.write(records.tobytes())


def write_ascii_stl(path, triangles: np.ndarray, name: str = "part") -> None:
    """Write ``triangles`` as ASCII STL with full float64 precision (repr)."""
    lines = [f"solid {name}"]
    for tri in np.asarray(triangles, dtype=np.float64):
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {x!r} {y!r} {z!r}" for x, y, z in tri.tolist()]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}")
    Path(path).write_text("\n".join(lines) + "\n")
