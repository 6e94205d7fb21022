#!/usr/bin/env python
"""The streaming numpy floor: the least a numpy program does to get a mesh's mass properties.

Reads the file in blocks, widens to float64, integrates (the signed-tetrahedron sums of volume,
first and second moments about a point near the part, as p3d sums them) and accumulates the
block totals; no checks of any kind (no finite test, no closed test, no error bound, no
bounds), nothing kept. A whole process doing only that is the floor the benchmarks hold
``p3d props`` against (issue 32): p3d does all of it plus its checks.

    python benchmarks/floor.py FILE        # binary STL, binary PLY (little-endian), ASCII STL,
                                           # GLB, 3MF (one mesh, no transforms: the floor's files)

Prints the volume (so that the benchmarks can check it against p3d's).
"""

from __future__ import annotations

import sys

import numpy as np

BLOCK = 1 << 14


def integrate(blocks) -> float:
    """Σ of the tetrahedron terms over ``(k, 3, 3)`` blocks; returns the volume."""
    totals = np.zeros(10)
    origin = None
    for block in blocks:
        p = np.empty((3, 3, len(block)))
        np.copyto(p, block.transpose(1, 2, 0))
        if origin is None:
            origin = p[0, :, 0].copy()
        p -= origin[None, :, None]
        a, b, c = p
        d = a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0])
        s = a + b + c
        totals[0] += d.sum()
        totals[1:4] += (d * s).sum(axis=1)
        for row, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)), start=4):
            totals[row] += (d * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j])).sum()
    return totals[0] / 6.0


def stl_binary_blocks(f, n: int):
    record = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
    f.seek(84)
    while n:
        k = min(BLOCK, n)
        yield np.frombuffer(f.read(50 * k), record)["corners"]
        n -= k


def ply_binary_blocks(f):
    """Little-endian binary PLY with one vertex element (x, y, z first) and triangle faces."""
    types = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8", "uchar": "u1", "uint8": "u1",
             "char": "i1", "int8": "i1", "short": "<i2", "ushort": "<u2", "int": "<i4", "int32": "<i4",
             "uint": "<u4", "uint32": "<u4"}
    elements, current = [], None
    while True:
        words = f.readline().split()
        if words[:1] == [b"end_header"]:
            break
        if words[:1] == [b"element"]:
            current = (words[1].decode(), int(words[2]), [])
            elements.append(current)
        elif words[:1] == [b"property"]:
            current[2].append([w.decode() for w in words[1:]])
    vertices = faces = None
    for name, count, props in elements:
        if name == "vertex":
            dtype = np.dtype([(p[-1], types[p[0]]) for p in props])
            data = np.frombuffer(f.read(dtype.itemsize * count), dtype)
            vertices = np.stack([data["x"], data["y"], data["z"]], axis=1)
        elif name == "face":
            (_, size, index, _), = props
            dtype = np.dtype([("n", types[size]), ("v", types[index], (3,))])
            faces = np.frombuffer(f.read(dtype.itemsize * count), dtype)["v"]
    for start in range(0, len(faces), BLOCK):
        yield vertices[faces[start:start + BLOCK]]


def stl_ascii_blocks(f):
    """``vertex x y z`` lines, parsed by numpy's float parser in chunks of whole facets."""
    carry = b""
    while True:
        chunk = f.read(1 << 22)
        text = carry + chunk
        if chunk:
            cut = text.rfind(b"endfacet")
            text, carry = text[:cut], text[cut:]
        words = text.split()
        numbers = [words[i + 1:i + 4] for i, w in enumerate(words) if w == b"vertex"]
        if numbers:
            yield np.array(numbers, dtype=np.float64).reshape(-1, 3, 3)
        if not chunk:
            return


def glb_blocks(f):
    """The first primitive of a GLB's first mesh: its POSITION and indices accessors read
    straight from the binary chunk (no node transforms, no sparse accessors: the floor's files)."""
    import json

    data = f.read()
    length = int(np.frombuffer(data[12:16], "<u4")[0])
    doc = json.loads(data[20:20 + length])
    binary = memoryview(data)[20 + length + 8:]
    kinds = {5121: "u1", 5123: "<u2", 5125: "<u4", 5126: "<f4"}

    def accessor(i: int) -> np.ndarray:
        a = doc["accessors"][i]
        view = doc["bufferViews"][a["bufferView"]]
        width = {"SCALAR": 1, "VEC3": 3}[a["type"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        dtype = np.dtype(kinds[a["componentType"]])
        return np.frombuffer(binary, dtype, a["count"] * width, start).reshape(-1, width)

    primitive = doc["meshes"][0]["primitives"][0]
    vertices = accessor(primitive["attributes"]["POSITION"])
    faces = accessor(primitive["indices"]).reshape(-1, 3)
    for start in range(0, len(faces), BLOCK):
        yield vertices[faces[start:start + BLOCK]]


def threemf_blocks(path: str):
    """The vertices and triangles of a 3MF's model part, found by regular expressions over the
    XML text and parsed by numpy's float parser (no XML tree, no transforms, no components)."""
    import re
    import zipfile

    with zipfile.ZipFile(path) as z:
        name = next(n for n in z.namelist() if n.lower().endswith(".model"))
        text = z.read(name)
    numbers = re.findall(rb'<vertex x="([^"]*)" y="([^"]*)" z="([^"]*)"', text)
    vertices = np.array(numbers, dtype=np.float64)
    corners = re.findall(rb'<triangle v1="([^"]*)" v2="([^"]*)" v3="([^"]*)"', text)
    faces = np.array(corners, dtype=np.int64)
    for start in range(0, len(faces), BLOCK):
        yield vertices[faces[start:start + BLOCK]]


def main(path: str) -> None:
    if path.lower().endswith(".3mf"):
        print(repr(float(integrate(threemf_blocks(path)))))
        return
    with open(path, "rb") as f:
        head = f.read(84)
        f.seek(0, 2)
        size = f.tell()
        f.seek(0)
        n = int(np.frombuffer(head[80:84], "<u4")[0]) if len(head) == 84 else -1
        if head.startswith(b"glTF"):
            volume = integrate(glb_blocks(f))
        elif head.startswith(b"ply"):
            volume = integrate(ply_binary_blocks(f))
        elif 84 + 50 * n == size:
            volume = integrate(stl_binary_blocks(f, n))
        else:
            volume = integrate(stl_ascii_blocks(f))
    print(repr(float(volume)))


if __name__ == "__main__":
    main(sys.argv[1])
