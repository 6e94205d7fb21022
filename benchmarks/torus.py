"""A grid torus of 2·u·v triangles (ring radius 3, tube radius 1) written as a benchmark mesh.

The benchmarks run this as a child process, so that their timing parent never imports numpy:

    python benchmarks/torus.py stl U V PATH --at X Y Z [--open] [--inward]   # binary STL, float32
    python benchmarks/torus.py ply U V PATH --at X Y Z [--soup]   # binary PLY, float64

``--at`` moves the torus's centre. ``--open`` removes the first two faces, which meet at a
corner: two holes, six boundary edges. ``--holes 0.01`` removes every 100th face (1 % of the
faces open: thousands of holes). ``--inward`` winds every face the other way. ``--soup`` gives
every triangle its own three vertices,
shrunk by 2^-20 towards its centroid, so that no two triangles share an edge.
"""

from __future__ import annotations

import argparse

import numpy as np


def grid_torus(u: int, v: int, at) -> tuple[np.ndarray, np.ndarray]:
    """Vertices ``(u·v, 3)`` float64 and faces ``(2·u·v, 3)``, wound outwards."""
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = 3.0 + np.cos(phi)
    vertices = np.stack([ring * np.cos(theta), ring * np.sin(theta), np.sin(phi)], axis=-1)
    vertices = vertices.reshape(-1, 3) + list(at)
    a = (i * v + j).reshape(-1)
    b = (((i + 1) % u) * v + j).reshape(-1)
    c = (((i + 1) % u) * v + (j + 1) % v).reshape(-1)
    d = (i * v + (j + 1) % v).reshape(-1)
    return vertices, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def write_stl(path: str, triangles: np.ndarray) -> None:
    """Binary STL, float32 corners, zero normals."""
    record = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    out = np.zeros(len(triangles), record)
    out["corners"] = triangles
    with open(path, "wb") as f:
        f.write(b"p3d check benchmark torus".ljust(80, b" "))
        f.write(np.uint32(len(triangles)).tobytes())
        out.tofile(f)


def write_ply_soup(path: str, triangles: np.ndarray) -> None:
    """Binary PLY, float64, three vertices of its own for every triangle."""
    n = len(triangles)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {3 * n}\n"
              "property double x\nproperty double y\nproperty double z\n"
              f"element face {n}\nproperty list uchar int vertex_indices\nend_header\n").encode()
    record = np.dtype([("k", "u1"), ("ids", "<i4", (3,))], align=False)
    face = np.zeros(n, record)
    face["k"] = 3
    face["ids"] = np.arange(3 * n, dtype=np.int32).reshape(n, 3)
    with open(path, "wb") as f:
        f.write(header)
        triangles.reshape(-1, 3).astype("<f8").tofile(f)
        face.tofile(f)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("format", choices=("stl", "ply"))
    parser.add_argument("u", type=int)
    parser.add_argument("v", type=int)
    parser.add_argument("path")
    parser.add_argument("--at", type=float, nargs=3, default=(0.0, 0.0, 0.0))
    parser.add_argument("--open", action="store_true", help="remove the first two faces")
    parser.add_argument("--soup", action="store_true", help="no two triangles share an edge")
    parser.add_argument("--inward", action="store_true", help="wind every face inward")
    parser.add_argument("--holes", type=float, default=0.0,
                        help="remove this fraction of the faces, evenly spread (0.01: every 100th face)")
    args = parser.parse_args(argv)
    vertices, faces = grid_torus(args.u, args.v, args.at)
    if args.open:
        faces = faces[2:]
    if args.holes:
        keep = np.ones(len(faces), dtype=bool)
        keep[::max(1, round(1 / args.holes))] = False
        faces = faces[keep]
    if args.inward:
        faces = faces[:, ::-1]
    if args.format == "stl":
        write_stl(args.path, vertices.astype(np.float32)[faces])
        return
    triangles = vertices[faces]
    if args.soup:
        centre = triangles.mean(axis=1, keepdims=True)
        triangles = centre + (triangles - centre) * (1 - 2.0 ** -20)
    write_ply_soup(args.path, triangles)


if __name__ == "__main__":
    main()
