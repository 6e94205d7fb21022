"""Fuzz targets: one per reader and one for the scene loader.

Each target takes arbitrary bytes and must end in a result or a ``P3DError``: any other
exception (``IndexError``, ``OverflowError``, ``RecursionError``, ...) is a bug, and so is a
crash or a hang, which the harness that drives the target sees. The same targets serve the
short hypothesis runs of the test suite (``tests/fuzz/test_fuzz.py``) and long coverage-guided
runs with atheris (``tests/fuzz/run_atheris.py``; see docs/fuzzing.md).
"""

from __future__ import annotations

import os
import struct
import tempfile
from pathlib import Path

import numpy as np

from p3d_cli.errors import P3DError
from p3d_cli.io import formats
from p3d_cli.io.raw import RawInput

REPO = Path(__file__).resolve().parents[2]

#: Bytes of the largest fuzz input: enough for every header and a few faces.
MAX_INPUT = 1 << 14


def measure_bytes(data: bytes, fmt: str):
    """Read ``data`` as format ``fmt`` and integrate it, as ``p3d props`` would: the
    ``PropsResult``, or None when p3d refused the input with a ``P3DError``."""
    from p3d_cli.exact import exact_props
    from p3d_cli.solid import Solid

    raw = RawInput("<fuzz>", None, data, len(data))
    try:
        mesh = formats.read(raw, fmt)
        result = exact_props(Solid("<fuzz>", mesh=mesh))
    except P3DError:
        return None
    volume = result.properties.volume
    assert isinstance(volume, float) and np.isfinite(volume), volume
    return result


def load_scene_bytes(data: bytes, steps: int = 0):
    """Parse and solve ``data`` as a scene file (one velocity solve, or ``steps`` steps of
    0.01 s), as ``p3d solve`` would: the ``SolveResult``, or None when p3d refused the scene with
    a ``P3DError``. A numpy RuntimeWarning is a bug too (an overflow must be one RangeError),
    and so is a non-finite number in the result."""
    import warnings

    from p3d_cli.constraints import load_scene, solve_scene

    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "scene.yaml")
        with open(path, "wb") as f:
            f.write(data)
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            try:
                result = solve_scene(load_scene(path), steps=steps, dt=0.01 if steps else None)
            except P3DError:
                return None
    _assert_finite_solve(result)
    return result


def _assert_finite_solve(result) -> None:
    numbers = [*result.kinetic_energy, *result.momentum, *result.angular_momentum, result.max_position_error]
    for body in result.bodies:
        numbers += [body.position, body.rotation, body.velocity, body.angular_velocity]
    for c in result.constraints:
        numbers += [c.impulse, c.error, c.position_error]
        if c.angular_impulse is not None:
            numbers.append(c.angular_impulse)
    for value in numbers:
        assert np.all(np.isfinite(value)), value


def seeds(name: str) -> list[bytes]:
    """Valid inputs of each target to mutate from: the bundled samples and examples."""
    samples = REPO / "sample_meshes"
    if name in ("scene", "scene_steps"):
        return [p.read_bytes() for p in sorted((REPO / "examples").glob("*.yaml"))]
    if name == "stl":
        return [(samples / "bracket.stl").read_bytes()[:MAX_INPUT], (samples / "tetrahedron.stl").read_bytes(),
                _binary_stl()]
    if name == "obj":
        return [(samples / "bracket.obj").read_bytes()]
    if name == "off":
        return [(samples / "cube.off").read_bytes()]
    if name == "ply":
        return [_ply("ascii"), _ply("binary_little_endian"), _ply("binary_big_endian")]
    if name in ("gltf", "glb", "3mf"):
        return _scene_seeds(name)
    raise KeyError(name)


def _scene_seeds(name: str) -> list[bytes]:
    """glTF JSON (buffers as data: URIs), GLB, and 3MF model XML: a two-material cube, nodes
    with TRS and matrices, a strip, sparse positions, instancing; components and items."""
    import base64
    import json

    from helpers.gltf_writer import CUBE_FACES, CUBE_VERTICES, TET_FACES, TET_VERTICES, Gltf
    from helpers.threemf_writer import component_object, mesh_object, model

    if name == "3mf":
        return [model([mesh_object(1, CUBE_VERTICES, CUBE_FACES, "cube"),
                       component_object(2, [(1, np.diag([1.0, 1.0, -1.0, 1.0]), None), (1, None, None)])],
                      [(2, None, None), (1, np.eye(4), None)], unit="inch").encode(),
                model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)]).encode()]
    doc = Gltf()
    cube = doc.mesh(doc.primitive(CUBE_VERTICES, CUBE_FACES[:6], index_dtype="uint16"),
                    doc.primitive(CUBE_VERTICES, CUBE_FACES[6:], index_dtype="uint8"))
    child = doc.node(doc.mesh(doc.primitive(CUBE_VERTICES, [4, 0, 5, 1, 6, 2, 7, 3, 4, 0], mode=5)), root=False,
                     matrix=[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1])
    doc.node(cube, rotation=[0.0, 0.0, 0.6, 0.8], scale=[1.0, 2.0, 1.0], children=[child])
    ext = {"attributes": {"TRANSLATION": doc.accessor(np.array([[0, 0, 0], [5, 0, 0]]))}}
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES, mode=4)), extensions={"EXT_mesh_gpu_instancing": ext})
    doc.json["extensionsUsed"] = ["EXT_mesh_gpu_instancing"]
    if name == "glb":
        return [doc.glb()]
    uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(doc.blob)).decode()
    return [json.dumps(doc.document(uri)).encode()]


def threemf_bytes(data: bytes):
    """A 3MF target: ``data`` is a whole package when it starts as a zip does, else the root
    model part's XML, zipped here (so that mutations reach the model reader, not only the zip's
    checksums)."""
    import io
    import zipfile

    if data[:2] != b"PK":
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_STORED) as archive:
            archive.writestr("3D/3dmodel.model", data)
        data = buffer.getvalue()
    return measure_bytes(data, "3mf")


_TET_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
_TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def _binary_stl() -> bytes:
    records = np.zeros(4, dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    records["v"] = _TET_V[_TET_F]
    return b"fuzz".ljust(80, b" ") + struct.pack("<I", 4) + records.tobytes()


def _ply(fmt: str) -> bytes:
    head = (f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
            "property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n").encode()
    if fmt == "ascii":
        body = "".join(f"{x} {y} {z}\n" for x, y, z in _TET_V) + "".join(f"3 {a} {b} {c}\n" for a, b, c in _TET_F)
        return head + body.encode()
    order = "<" if fmt.endswith("little_endian") else ">"
    body = b"".join(struct.pack(order + "3f", *v) for v in _TET_V)
    body += b"".join(struct.pack(order + "B3i", 3, *f) for f in _TET_F)
    return head + body


TARGETS = {
    "stl": lambda data: measure_bytes(data, "stl"),
    "obj": lambda data: measure_bytes(data, "obj"),
    "ply": lambda data: measure_bytes(data, "ply"),
    "off": lambda data: measure_bytes(data, "off"),
    "gltf": lambda data: measure_bytes(data, "gltf"),
    "glb": lambda data: measure_bytes(data, "gltf"),
    "3mf": threemf_bytes,
    "scene": load_scene_bytes,
    "scene_steps": lambda data: load_scene_bytes(data, steps=3),
}
