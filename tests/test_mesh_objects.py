"""Other libraries' mesh objects are measured as they are, by duck typing: a ``trimesh.Trimesh``
(``vertices``, ``faces``) and a ``meshio.Mesh`` (``points``, ``cells`` blocks), with neither
library imported by p3d."""

from __future__ import annotations

import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

import p3d_cli as p3d

from helpers.meshes import CUBE_FACES, CUBE_VERTICES

V = CUBE_VERTICES * [2.0, 3.0, 5.0] + [1.0, -2.0, 0.5]
F = CUBE_FACES
NUMBERS = ("volume", "mass", "center_of_mass", "inertia", "inertia_origin", "principal_moments", "bounds",
           "closed", "faces")


def numbers(result) -> dict:
    record = result.to_dict()
    return {key: record[key] for key in NUMBERS}


def test_an_object_with_vertices_and_faces_is_the_same_as_the_arrays():
    thing = SimpleNamespace(vertices=V, faces=F)
    result = p3d.props(thing, density=2.5)
    assert numbers(result) == numbers(p3d.props((V, F), density=2.5))
    assert (result.facts.source, result.facts.format) == ("<SimpleNamespace>", "trimesh")
    assert result.volume == 30.0
    assert p3d.bounds(thing).max.tolist() == [3.0, 1.0, 5.5]
    assert p3d.check(thing).ok and p3d.self_intersections(thing).count == 0


def test_an_object_with_points_and_cells_is_read_as_meshio_reads_a_file():
    quads = SimpleNamespace(type="quad", data=np.array([[0, 1, 2, 3]]))
    thing = SimpleNamespace(points=V, cells=[SimpleNamespace(type="triangle", data=F)])
    result = p3d.props(thing)
    assert numbers(result) == numbers(p3d.props((V, F)))
    assert (result.facts.source, result.facts.format) == ("<SimpleNamespace>", "meshio")
    assert p3d.props(SimpleNamespace(points=V, cells=[quads])).facts.faces == 2   # a quad is two triangles
    tetra = SimpleNamespace(points=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]),
                            cells=[SimpleNamespace(type="tetra", data=np.array([[0, 1, 2, 3]]))])
    assert p3d.props(tetra).volume == pytest.approx(1 / 6, rel=1e-15)


@pytest.mark.parametrize("thing, error, match", [
    (SimpleNamespace(vertices=V, faces=F + 100), p3d.InputError, "outside 0..7"),
    (SimpleNamespace(vertices=V[:, :2], faces=F), p3d.UsageError, r"\(m, 3\) array"),
    (SimpleNamespace(points=V, cells=[SimpleNamespace(type="hexahedron", data=np.arange(8)[None])]),
     p3d.FormatError, "hexahedron cells, which p3d does not integrate"),
    (SimpleNamespace(points=V, cells=[SimpleNamespace(type="line", data=np.array([[0, 1]]))]),
     p3d.InputError, "no faces"),
    (SimpleNamespace(points=V), p3d.UsageError, "cannot measure a SimpleNamespace"),
])
def test_a_bad_mesh_object_is_one_clear_error(thing, error, match):
    with pytest.raises(error, match=match) as info:
        p3d.props(thing)
    assert isinstance(info.value, ValueError)


def test_trimesh_and_meshio_objects_agree_with_trimesh_itself():
    trimesh = pytest.importorskip("trimesh")
    meshio = pytest.importorskip("meshio")
    mesh = trimesh.creation.box(extents=(2.0, 3.0, 5.0))
    mesh.apply_translation([1.0, -2.0, 0.5])
    result = p3d.props(mesh, density=7.0)
    assert result.facts.source == "<Trimesh>"
    assert result.mass == pytest.approx(mesh.volume * 7.0, rel=1e-14)
    mesh.density = 7.0
    np.testing.assert_allclose(result.center_of_mass, mesh.center_mass, rtol=1e-14)
    np.testing.assert_allclose(result.inertia, mesh.moment_inertia, rtol=1e-13, atol=1e-12)
    as_meshio = meshio.Mesh(mesh.vertices, [("triangle", mesh.faces)])
    assert numbers(p3d.props(as_meshio)) == numbers(p3d.props(mesh))
    assert p3d.props(as_meshio).facts.source == "<Mesh>"


def test_neither_library_is_imported_to_read_their_objects():
    code = ("import sys; from types import SimpleNamespace as N; import numpy as np; import p3d_cli as p3d; "
            "v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]); f = np.array([[0, 2, 1], [0, 1, 3], "
            "[0, 3, 2], [1, 2, 3]]); p3d.props(N(vertices=v, faces=f)); "
            "p3d.props(N(points=v, cells=[N(type='triangle', data=f)])); "
            "print(sorted(m for m in ('trimesh', 'meshio') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
