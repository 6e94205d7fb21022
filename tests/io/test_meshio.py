"""The meshio fallback: extension and name lookup, tetrahedra integrated exactly, surface
cells fan-split, stdin, meshio's failures turned into FormatError, meshio imported lazily."""

from __future__ import annotations

import io
import subprocess
import sys
from fractions import Fraction

import numpy as np
import pytest

from p3d_cli.errors import FormatError, InputError, MissingExtraError, UnknownFormatError
from p3d_cli.io import detect_format, is_mesh_path, load_mesh, meshio_backend
from p3d_cli.io.raw import open_input
import p3d_cli as p3d

meshio = pytest.importorskip("meshio")

CUBE_V = np.array([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
                  dtype=float)
CUBE_QUADS = np.array([(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)])
# The cube [0, 1]^3 as six positively oriented tetrahedra around the diagonal 0-6.
CUBE_TETS = np.array([(0, 1, 2, 6), (0, 2, 3, 6), (0, 3, 7, 6), (0, 7, 4, 6), (0, 4, 5, 6), (0, 5, 1, 6)])


def test_extension_and_name_lookup():
    assert meshio_backend.knows_extension(".vtu") and meshio_backend.knows_extension(".msh")
    for ours in (".stl", ".obj", ".ply", ".off"):
        assert not meshio_backend.knows_extension(ours)
    assert not meshio_backend.knows_extension(".xyz") and not meshio_backend.knows_extension("")
    assert meshio_backend.knows_format("vtu") and meshio_backend.knows_format("gmsh")
    assert not meshio_backend.knows_format("stl") and not meshio_backend.knows_format("nonsense")
    assert meshio_backend.format_for_extension(".msh") == "gmsh"
    assert meshio_backend.format_for_extension(".vtu") == "vtu"
    with pytest.raises(KeyError):
        meshio_backend.format_for_extension(".xyz")
    assert is_mesh_path("part.vtu") and not is_mesh_path("notes.txt")


def test_companion_files_are_skipped_without_asking_meshio(tmp_path):
    from p3d_cli import io as p3d_io

    # The skip list must never hide a format meshio reads.
    assert not [ext for ext in p3d_io.NEVER_MESHES if ext and meshio_backend.knows_extension(ext)]
    for name in ("part.stl", "part.mtl", "notes.txt", "README", "list.json"):
        (tmp_path / name).write_bytes(b"")
    code = ("import sys; from p3d_cli.batch.inputs import expand_inputs; "
            f"print([p.rsplit('/', 1)[1] for p in expand_inputs([{str(tmp_path)!r}])], 'meshio' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split() == ["['part.stl']", "False"]


def test_tetrahedra_give_exact_volume_centre_and_inertia(tmp_path):
    path = str(tmp_path / "cube.msh")
    meshio.write(path, meshio.Mesh(CUBE_V, [("tetra", CUBE_TETS)]), file_format="gmsh22", binary=False)
    mesh = load_mesh(path)
    assert mesh.format == "meshio:gmsh" and mesh.face_count == 6
    assert mesh.tetrahedra.shape == (6, 4, 3) and mesh.tetrahedra.dtype == np.float64
    assert list(mesh.read_blocks()) == []
    props = p3d.props(path).properties
    assert props.volume == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(props.center_of_mass, [0.5] * 3, rtol=0, atol=1e-15)
    np.testing.assert_allclose(props.inertia, np.eye(3) / 6, rtol=0, atol=1e-15)


def test_two_tetrahedra_vtu_exact(tmp_path):
    points = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1.0]])
    path = str(tmp_path / "two.vtu")
    meshio.write(path, meshio.Mesh(points, [("tetra", np.array([[0, 1, 2, 3], [1, 2, 3, 4]]))]))
    props = p3d.props(path).properties
    # Volumes 1/6 and 1/3, centroids (1/4, 1/4, 1/4) and (1/2, 1/2, 1/2).
    volume = Fraction(1, 6) + Fraction(1, 3)
    centre = (Fraction(1, 6) * Fraction(1, 4) + Fraction(1, 3) * Fraction(1, 2)) / volume
    assert props.volume == pytest.approx(float(volume), rel=1e-15)
    np.testing.assert_allclose(props.center_of_mass, [float(centre)] * 3, rtol=1e-15)


def test_surface_quads_and_triangles_are_fan_split(tmp_path):
    path = str(tmp_path / "cube.vtu")
    cells = [("quad", CUBE_QUADS[:4]), ("triangle", np.array([[2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]))]
    meshio.write(path, meshio.Mesh(CUBE_V, cells))
    mesh = load_mesh(path)
    assert mesh.format == "meshio:vtu" and mesh.tetrahedra is None and mesh.face_count == 12
    tris = mesh.triangles()
    expected = [CUBE_V[[q[0], q[i], q[i + 1]]] for q in CUBE_QUADS[:4] for i in (1, 2)]
    np.testing.assert_array_equal(tris[:8], np.array(expected))
    assert p3d.props(path).properties.volume == pytest.approx(1.0, rel=1e-15)


def test_polygon_cells(tmp_path):
    hexagon = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 6, endpoint=False)])
    points = np.vstack([hexagon, [[0, 0, 1.0]]])
    mesh = meshio.Mesh(points, [("polygon", np.array([[5, 4, 3, 2, 1, 0]])),
                                ("triangle", np.array([[i, (i + 1) % 6, 6] for i in range(6)]))])
    path = str(tmp_path / "pyramid.vtk")
    meshio.write(path, mesh, binary=False)
    loaded = load_mesh(path)
    assert loaded.face_count == 4 + 6
    np.testing.assert_array_equal(loaded.triangles()[:4], points[[[5, 4, 3], [5, 3, 2], [5, 2, 1], [5, 1, 0]]])
    area = 6 * np.sqrt(3) / 4
    assert p3d.props(path).properties.volume == pytest.approx(area / 3, rel=1e-14)


def test_float32_points_reported(tmp_path):
    path = str(tmp_path / "f.vtu")
    meshio.write(path, meshio.Mesh(CUBE_V.astype(np.float32), [("tetra", CUBE_TETS)]))
    assert load_mesh(path).coordinate_dtype == "float32"


def test_stdin_goes_through_a_temporary_file(tmp_path):
    path = tmp_path / "cube.vtu"
    meshio.write(str(path), meshio.Mesh(CUBE_V, [("tetra", CUBE_TETS)]))
    result = p3d.props("-", format="vtu", stdin=io.BytesIO(path.read_bytes()))
    assert result.properties.volume == pytest.approx(1.0, rel=1e-15)
    raw = open_input("-", io.BytesIO(path.read_bytes()))
    assert detect_format(raw, "gmsh") == "meshio:gmsh"


# --- errors ------------------------------------------------------------------------------

@pytest.mark.parametrize("name, data", [
    ("bad.vtu", b"<VTKFile garbage"),
    ("bad.vtu", b"<?xml version='1.0'?>\n<VTKFile type='UnstructuredGrid'><Unstructured"),
    ("bad.msh", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n8\n1 0 0\n"),
    ("bad.msh", b"\x00\x01garbage"),
    ("bad.vtk", b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 9 double\n1 2"),
])
def test_corrupt_files_become_format_errors(tmp_path, name, data):
    path = tmp_path / name
    path.write_bytes(data)
    with pytest.raises(FormatError) as info:
        load_mesh(str(path))
    assert "meshio could not read it" in info.value.what and info.value.hint


def test_hexahedra_are_refused(tmp_path):
    path = str(tmp_path / "hex.vtu")
    meshio.write(path, meshio.Mesh(CUBE_V, [("hexahedron", np.arange(8)[None])]))
    with pytest.raises(FormatError) as info:
        load_mesh(path)
    assert "hexahedron" in info.value.what and "tetrahedra" in info.value.hint


def test_no_cells_is_input_error(tmp_path):
    path = str(tmp_path / "points.vtu")
    meshio.write(path, meshio.Mesh(CUBE_V, [("vertex", np.arange(8)[:, None])]))
    with pytest.raises(InputError) as info:
        load_mesh(path)
    assert "no faces" in info.value.what and "vertex" in info.value.what


def test_cell_index_out_of_range():
    mesh = meshio.Mesh(CUBE_V, [("triangle", np.array([[0, 1, 9]]))])
    with pytest.raises(FormatError) as info:
        meshio_backend._source("x.vtu", "vtu", mesh)
    assert "point 9" in info.value.what and "8 points" in info.value.what


def test_missing_meshio_names_the_package(tmp_path, monkeypatch):
    path = tmp_path / "cube.vtu"
    meshio.write(str(path), meshio.Mesh(CUBE_V, [("tetra", CUBE_TETS)]))
    monkeypatch.setitem(sys.modules, "meshio", None)  # makes 'import meshio' fail
    with pytest.raises(MissingExtraError) as info:
        meshio_backend.load(open_input(str(path)), "vtu")
    assert "pip install meshio" in info.value.hint
    assert not meshio_backend.knows_extension(".vtu")


def test_meshio_is_imported_lazily():
    code = "import sys, p3d_cli.io; print('meshio' in sys.modules, 'trimesh' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "False"]


# --- issue 12 and 17: mixed cells, files that are no mesh, lying counts ----------------

def test_tetrahedra_and_triangles_say_which_was_measured(tmp_path):
    path = str(tmp_path / "mixed.vtu")
    boundary = CUBE_QUADS[:, [0, 1, 2]]   # one triangle per side: surface cells beside the volume
    meshio.write(path, meshio.Mesh(CUBE_V, [("tetra", CUBE_TETS), ("triangle", boundary)]))
    mesh = load_mesh(path)
    assert mesh.tetrahedra.shape == (6, 4, 3)
    assert len(mesh.warnings) == 1
    assert "6 tetrahedra" in mesh.warnings[0] and "6 triangle" in mesh.warnings[0]
    assert "tetrahedra were measured" in mesh.warnings[0]
    assert p3d.props(path).properties.volume == pytest.approx(1.0, rel=1e-15)


def test_files_that_are_no_mesh_are_format_errors(tmp_path):
    path = tmp_path / "notes.dat"
    path.write_bytes(b"hello world\n1 2 3\n")
    with pytest.raises(FormatError) as info:
        load_mesh(str(path))
    assert "meshio could not read it" in info.value.what and info.value.hint


def test_an_xml_file_that_is_no_dolfin_mesh_says_what_it_is(tmp_path):
    # meshio reads .xml as DOLFIN XML only: any other root element is refused before it.
    path = tmp_path / "config.xml"
    path.write_bytes(b'<?xml version="1.0"?>\n<cfg:config xmlns:cfg="x"><a>1</a></cfg:config>\n')
    with pytest.raises(UnknownFormatError) as info:
        load_mesh(str(path))
    assert info.value.what.startswith("is an XML file whose root element is <config>, not a mesh")
    assert "--format NAME" in info.value.hint


@pytest.mark.parametrize("name, data, claim", [
    ("lie.vtk", b"# vtk DataFile Version 4.2\nx\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 100000000000 double\n"
     b"0 0 0\n", "100000000000 points"),
    ("lie.msh", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1000000000000\n1 0 0 0\n$EndNodes\n",
     "1000000000000 nodes"),
    ("lie4.msh", b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1000000000000 1 1000000000000\n2 1 0 1\n1\n"
     b"0 0 0\n$EndNodes\n", "1000000000000 nodes"),
])
def test_lying_counts_are_refused_before_meshio_allocates(tmp_path, name, data, claim):
    import tracemalloc
    path = tmp_path / name
    path.write_bytes(data)
    tracemalloc.start()
    try:
        with pytest.raises(FormatError) as info:
            load_mesh(str(path))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert claim in info.value.what and peak < 50_000_000
