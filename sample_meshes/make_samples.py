"""Regenerate the sample meshes in this folder: ``python sample_meshes/make_samples.py``.

Every sample is built here from exact coordinates with numpy only, so its mass properties are
known in closed form (see README.md beside this file).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def bracket() -> tuple[np.ndarray, np.ndarray]:
    """An L-shaped bracket: the 40 x 10 x 30 box minus the 30 x 10 x 25 box above its foot.

    Outline in the x-z plane (counter-clockwise), extruded along y from 0 to 10.
    """
    outline = np.array([[0, 0], [40, 0], [40, 5], [10, 5], [10, 30], [0, 30]], dtype=np.float64)
    n = len(outline)
    verts = np.array([[x, y, z] for y in (0.0, 10.0) for x, z in outline])
    faces = []
    # Side walls: outline edge i -> i+1 on y=0 (index i) and y=10 (index n+i).
    for i in range(n):
        j = (i + 1) % n
        faces += [[i, j, n + j], [i, n + j, n + i]]
    # Caps: the L split into two rectangles [0,1,2,3']... triangulated by hand.
    cap = [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]
    faces += [[a, c, b] for a, b, c in cap]            # y = 0 faces -y: reversed
    faces += [[n + a, n + b, n + c] for a, b, c in cap]  # y = 10 faces +y
    return verts, np.array(faces)[:, ::-1]  # wound so that normals point out of the solid


def write_binary_stl(path: Path, triangles: np.ndarray, header: bytes) -> None:
    with open(path, "wb") as f:
        f.write(header.ljust(80, b" "))
        f.write(struct.pack("<I", len(triangles)))
        for tri in triangles.astype(np.float32):
            f.write(struct.pack("<3f", 0, 0, 0) + tri.tobytes() + b"\0\0")


def main() -> None:
    verts, faces = bracket()
    # The header starts with 'solid', as many CAD exporters write it: p3d still reads binary.
    write_binary_stl(HERE / "bracket.stl", verts[faces], b"solid bracket (binary STL written by make_samples.py)")
    # The same bracket as OBJ with quads where the outline has rectangles.
    lines = ["# L bracket, 40 x 10 x 30, written by make_samples.py", "o bracket"]
    lines += [f"v {x:g} {y:g} {z:g}" for x, y, z in verts]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in faces]
    (HERE / "bracket.obj").write_text("\n".join(lines) + "\n")
    # A regular tetrahedron, ASCII STL.
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64)
    tris = tet[[[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]]
    text = ["solid tetrahedron"]
    for t in tris:
        text += ["  facet normal 0 0 0", "    outer loop"]
        text += [f"      vertex {x:g} {y:g} {z:g}" for x, y, z in t]
        text += ["    endloop", "  endfacet"]
    text.append("endsolid tetrahedron")
    (HERE / "tetrahedron.stl").write_text("\n".join(text) + "\n")
    # A unit cube as OFF with quad faces.
    cube = ["OFF", "8 6 12"]
    cube += [f"{x} {y} {z}" for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    cube += ["4 0 1 3 2", "4 4 6 7 5", "4 0 4 5 1", "4 2 3 7 6", "4 0 2 6 4", "4 1 5 7 3"]
    (HERE / "cube.off").write_text("\n".join(cube) + "\n")


if __name__ == "__main__":
    main()
