"""The mesh writers: what p3d writes it reads back to the same bits, and nothing is rounded."""

from __future__ import annotations

import numpy as np
import pytest

import p3d_cli as p3d
from p3d_cli.errors import OutputError, UsageError
from p3d_cli.io.writers import output_format, write_mesh

VERTICES = np.array([[0.1, -0.0, 1e-300], [1.0 / 3.0, 2.5e15, -7.25], [3.0, 0.5, 1.0], [-1e-7, 4.0, 2.0]])
FACES = np.array([[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]])


@pytest.mark.parametrize("ext", [".ply", ".obj", ".off"])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_indexed_formats_read_back_bit_for_bit(tmp_path, ext, dtype):
    vertices = VERTICES.astype(dtype)
    path = write_mesh(tmp_path / f"m{ext}", vertices, FACES)
    mesh = p3d.load_mesh(str(path))
    back = mesh.triangles()
    # PLY keeps the dtype; text formats are read as float64, each value the one written.
    assert back.dtype == (dtype if ext == ".ply" else np.float64)
    assert np.array_equal(back.astype(np.float64), vertices[FACES].astype(np.float64))
    assert np.array_equal(np.signbit(back), np.signbit(vertices[FACES]))     # -0.0 stays -0.0


def test_stl_is_binary_float32_with_the_triangles_as_given(tmp_path):
    triangles = VERTICES.astype(np.float32)[FACES]
    triangles[0, 0, 1] = np.float32(-0.0)
    path = write_mesh(tmp_path / "m.stl", None, None, triangles=triangles)
    assert path.stat().st_size == 84 + 50 * 4
    mesh = p3d.load_mesh(str(path))
    assert mesh.format == "stl-binary" and mesh.triangles().tobytes() == triangles.tobytes()
    record = np.frombuffer(path.read_bytes()[84:], dtype=[("n", "<f4", 3), ("c", "<f4", (3, 3)), ("a", "<u2")])
    wide = triangles.astype(np.float64)
    normal = np.cross(wide[:, 1] - wide[:, 0], wide[:, 2] - wide[:, 0])
    assert np.allclose(record["n"], normal / np.linalg.norm(normal, axis=1)[:, None], atol=1e-7)


def test_stl_refuses_float64_it_would_round(tmp_path):
    with pytest.raises(OutputError, match="1 of the float64 coordinates|would be rounded"):
        write_mesh(tmp_path / "m.stl", VERTICES, FACES)
    assert not (tmp_path / "m.stl").exists()
    exact = VERTICES.astype(np.float32).astype(np.float64)     # float64 holding float32 values
    write_mesh(tmp_path / "m.stl", exact, FACES)
    assert np.array_equal(p3d.load_mesh(str(tmp_path / "m.stl")).triangles(), exact[FACES].astype(np.float32))


def test_the_format_comes_from_the_extension_or_the_name(tmp_path):
    assert output_format("a.STL") == "stl" and output_format("a.obj", "ply") == "ply"
    with pytest.raises(UsageError, match="cannot write a mesh to extension '.glb'"):
        output_format("a.glb")
    with pytest.raises(UsageError, match="does not write 'gltf'"):
        output_format("a.stl", "gltf")


def test_an_input_is_never_written_over(tmp_path):
    path = tmp_path / "in.obj"
    write_mesh(path, VERTICES, FACES)
    before = path.read_bytes()
    with pytest.raises(OutputError, match="would overwrite the input"):
        write_mesh(path, VERTICES[:, ::-1].copy(), FACES, inputs=[path])
    assert path.read_bytes() == before
    write_mesh(path, VERTICES[:, ::-1].copy(), FACES, inputs=[path], in_place=True)
    assert path.read_bytes() != before
