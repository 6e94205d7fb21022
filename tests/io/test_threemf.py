"""3MF read by p3d's own reader, construct by construct, against the exact integrals of the
placed triangles (``exact.py``). Every package is written here by ``helpers.threemf_writer``
from the specification, with transforms and units that change the answer."""

from __future__ import annotations

import math
import zipfile
import zlib

import numpy as np
import pytest
from helpers.exact_check import assert_exact
from helpers.gltf_writer import CUBE_FACES, CUBE_VERTICES, TET_FACES, TET_VERTICES, placed, trs
from helpers.threemf_writer import component_object, mesh_object, model, package

import p3d_cli as p3d
from p3d_cli.errors import FormatError, InputError
from p3d_cli.io.threemf import model as threemf_model

AXIS = np.array([2.0, -1.0, 2.0]) / 3.0
TURN = trs((1.5, -2.0, 0.25), (*(math.sin(0.3) * AXIS), math.cos(0.3)), (1.0, 1.0, 1.0))
INCH = 0.0254


@pytest.fixture(params=["fast", "streamed"])
def path_kind(request, monkeypatch):
    """Every test runs on both roads through a model part: read whole with the fast lists, and
    streamed element by element (what parts over FAST_PART_BYTES take)."""
    if request.param == "streamed":
        monkeypatch.setattr(threemf_model, "FAST_PART_BYTES", 0)
    return request.param


def test_cube_in_two_materials_is_one_closed_cube(tmp_path, path_kind):
    materials = ('<m:basematerials id="9"><m:base name="red" displaycolor="#FF0000"/>'
                 '<m:base name="blue" displaycolor="#0000FF"/></m:basematerials>')
    cube = mesh_object(1, CUBE_VERTICES, CUBE_FACES, "cube")
    # Triangles of the first half in material 0, the rest in material 1 (per-triangle pid/p1).
    half = cube.split("<triangle ")
    cube = "<triangle ".join(half[:5] + [t.replace("/>", ' pid="9" p1="1"/>', 1) for t in half[5:]])
    cube = cube.replace('type="model"', 'type="model" pid="9" pindex="0"')
    ns = ' xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02"'
    path = package(tmp_path / "cube.3mf", model([materials, cube], [(1, None, None)], namespaces=ns))
    result = p3d.props(path, output_units="mm")
    assert result.properties.volume == 1.0 and result.facts.closed is True and not result.parts
    assert p3d.check(path).ok


def test_items_with_transforms_in_inches_and_a_mirror(tmp_path, path_kind):
    mirror = np.diag([1.0, -1.0, 1.0, 1.0]) @ trs((0.0, 40.0, 0.0))
    root = model([mesh_object(1, TET_VERTICES, TET_FACES, "tet"), mesh_object(2, CUBE_VERTICES, CUBE_FACES, "cube")],
                 [(1, TURN, None), (2, mirror, None), (1, None, None)], unit="inch")
    result = p3d.props(package(tmp_path / "items.3mf", root))
    assert result.units["mesh_length"] == "in"
    assert [p.details["name"] for p in result.parts] == ["tet", "cube", "tet-2"]
    assert_exact(result.parts[0], placed(TET_VERTICES, TET_FACES, TURN), INCH)
    assert_exact(result.parts[1], placed(CUBE_VERTICES, CUBE_FACES, mirror), INCH)
    assert result.parts[1].properties.volume > 0
    whole = np.concatenate([placed(TET_VERTICES, TET_FACES, TURN), placed(CUBE_VERTICES, CUBE_FACES, mirror),
                            placed(TET_VERTICES, TET_FACES)])
    assert_exact(result, whole, INCH)


@pytest.mark.parametrize("unit, metres", [("micron", 1e-6), ("centimeter", 1e-2), ("foot", 0.3048),
                                          ("meter", 1.0), (None, 1e-3)])
def test_units(tmp_path, unit, metres):
    root = model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, TURN, None)], unit=unit)
    result = p3d.props(package(tmp_path / "u.3mf", root))
    assert_exact(result, placed(TET_VERTICES, TET_FACES, TURN), metres)


def grid(count: int, step: float) -> list[np.ndarray]:
    return [trs((step * i, 0.0, 0.0)) for i in range(count)]


def test_component_arrays_in_three_levels_lose_nothing(tmp_path, path_kind):
    """Issue 27: 100 cubes in 10 components came out at 75 % of the volume, 1,000 in three
    levels at 14 %. Here 10 x 10 x 10 unit cubes, each level moved by a different step."""
    objects = [mesh_object(1, CUBE_VERTICES, CUBE_FACES, "cube"),
               component_object(2, [(1, m, None) for m in grid(10, 2.0)], "row"),
               component_object(3, [(2, trs((0.0, 3.0 * j, 0.0)), None) for j in range(10)], "layer"),
               component_object(4, [(3, trs((0.0, 0.0, 5.0 * k)), None) for k in range(10)], "block")]
    result = p3d.props(package(tmp_path / "block.3mf", model(objects, [(4, TURN, None)])), output_units="mm")
    assert len(result.parts) == 1000 and result.facts.faces == 12_000
    assert result.properties.volume == pytest.approx(1000.0, rel=1e-12)
    moves = [TURN @ trs((0.0, 0.0, 5.0 * k)) @ trs((0.0, 3.0 * j, 0.0)) @ trs((2.0 * i, 0.0, 0.0))
             for k in range(10) for j in range(10) for i in range(10)]
    assert_exact(result, np.concatenate([placed(CUBE_VERTICES, CUBE_FACES, m) for m in moves]))


def test_production_parts_count_as_often_as_referenced(tmp_path, path_kind):
    """Issue 26/27: components in other model parts (p:path) read 27x too large, and an
    external part referenced twice counted four times. Here the external part holds a
    tetrahedron and its own build section (which a consumer must ignore); the root places it
    by two items and once more through a component, beside a local cube."""
    external = model([mesh_object(5, TET_VERTICES, TET_FACES, "tet")], [(5, None, None), (5, trs((9, 9, 9)), None)])
    far = trs((100.0, 0.0, 0.0))
    root = model([mesh_object(1, CUBE_VERTICES, CUBE_FACES, "cube"),
                  component_object(2, [(5, TURN, "/3D/Objects/tet.model"), (1, far, None)], "pair")],
                 [(5, None, "/3D/Objects/tet.model"), (5, trs((0.0, 50.0, 0.0)), "/3D/Objects/tet.model"),
                  (2, None, None)])
    path = package(tmp_path / "prod.3mf", root, {"3D/Objects/tet.model": external})
    result = p3d.props(path, output_units="mm")
    assert [p.details["name"] for p in result.parts] == ["tet", "tet-2", "tet-3", "cube"]
    expected = [placed(TET_VERTICES, TET_FACES), placed(TET_VERTICES, TET_FACES, trs((0.0, 50.0, 0.0))),
                placed(TET_VERTICES, TET_FACES, TURN), placed(CUBE_VERTICES, CUBE_FACES, far)]
    assert result.properties.volume == pytest.approx(3 * 5.0 + 1.0, rel=1e-12)
    assert_exact(result, np.concatenate(expected))


def test_only_model_parts_are_inflated(tmp_path, monkeypatch):
    """Issue 27: a 3MF's unused 1 GiB thumbnail was read into memory. Here the thumbnail is a
    member whose compressed bytes are corrupt: reading it would fail, and the file reads."""
    root = model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)])
    thumbnail = b"\x89PNG" + np.random.default_rng(1).bytes(1 << 16)
    path = package(tmp_path / "thumb.3mf", root, {"Metadata/thumbnail.png": thumbnail})
    data = bytearray(path.read_bytes())
    at = data.find(b"Metadata/thumbnail.png") + len("Metadata/thumbnail.png")
    data[at:at + 200] = bytes(range(200))         # the thumbnail's deflate stream, destroyed
    path.write_bytes(bytes(data))
    with pytest.raises((zipfile.BadZipFile, zlib.error)):
        zipfile.ZipFile(path).read("Metadata/thumbnail.png")
    opened = []
    real_open = zipfile.ZipFile.open
    monkeypatch.setattr(zipfile.ZipFile, "open", lambda self, name, *a, **k: (
        opened.append(getattr(name, "filename", name)), real_open(self, name, *a, **k))[1])
    assert_exact(p3d.props(path, output_units="mm"), placed(TET_VERTICES, TET_FACES))
    assert "Metadata/thumbnail.png" not in opened and "3D/3dmodel.model" in opened


@pytest.mark.parametrize("required, ok", [("m p", True), ("x", False)])
def test_required_extensions(tmp_path, required, ok):
    ns = (' xmlns:m="http://schemas.microsoft.com/3dmanufacturing/material/2015/02"'
          ' xmlns:x="http://example.com/geometry-changing/2030"')
    root = model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)], required=required, namespaces=ns)
    path = package(tmp_path / "req.3mf", root)
    if ok:
        assert_exact(p3d.props(path, output_units="mm"), placed(TET_VERTICES, TET_FACES))
    else:
        with pytest.raises(FormatError, match="example.com/geometry-changing.*must then refuse"):
            p3d.props(path)


BEAMS = ('<b:beamlattice minlength="0.1" radius="0.5"><b:beams><b:beam v1="0" v2="3"/></b:beams>'
         "</b:beamlattice>")
BEAM_NS = ' xmlns:b="http://schemas.microsoft.com/3dmanufacturing/beamlattice/2017/02"'


def test_beam_lattice_is_refused_by_name_when_placed(tmp_path, path_kind):
    placed_lattice = model([mesh_object(1, TET_VERTICES, TET_FACES, "truss", extra=BEAMS)], [(1, None, None)],
                           namespaces=BEAM_NS)
    with pytest.raises(FormatError, match="truss.*beam lattice"):
        p3d.props(package(tmp_path / "beams.3mf", placed_lattice))
    unused = model([mesh_object(1, TET_VERTICES, TET_FACES), mesh_object(2, TET_VERTICES, TET_FACES, extra=BEAMS)],
                   [(1, None, None)], namespaces=BEAM_NS)
    assert_exact(p3d.props(package(tmp_path / "unused.3mf", unused), output_units="mm"),
                 placed(TET_VERTICES, TET_FACES))


def test_support_objects_are_measured_with_a_warning(tmp_path):
    root = model([mesh_object(1, TET_VERTICES, TET_FACES), mesh_object(2, CUBE_VERTICES, CUBE_FACES, kind="support")],
                 [(1, None, None), (2, trs((10.0, 0.0, 0.0)), None)])
    result = p3d.props(package(tmp_path / "sup.3mf", root), output_units="mm")
    assert any("of type 'support'" in w for w in result.warnings)
    assert result.properties.volume == pytest.approx(6.0, rel=1e-12)


def test_empty_build_says_so(tmp_path):
    with pytest.raises(InputError, match="build lists no items"):
        p3d.props(package(tmp_path / "none.3mf", model([mesh_object(1, TET_VERTICES, TET_FACES)], [])))


def test_non_canonical_markup_takes_the_careful_road(tmp_path):
    """Single quotes, another attribute order, an entity in a number, a comment: all read."""
    text = ("<object id='1' type='model'><mesh><vertices>"
            + "".join(f"<vertex z='{z!r}' x = '{x!r}' y='{y!r}'/>" for x, y, z in TET_VERTICES.tolist())
            + "</vertices><triangles><!-- four -->"
            + "".join(f"<triangle v3='{c}' v1='{a}' v2='&#{48 + b};'/>" for a, b, c in TET_FACES.tolist())
            + "</triangles></mesh></object>")
    path = package(tmp_path / "odd.3mf", model([text], [(1, TURN, None)]))
    assert_exact(p3d.props(path, output_units="mm"), placed(TET_VERTICES, TET_FACES, TURN))


def test_gltf_and_3mf_runs_import_no_scene_library(tmp_path):
    """p3d's own readers: reading GLB and 3MF imports neither trimesh (0.6-0.9 s to import) nor
    the libraries its loaders needed."""
    import subprocess
    import sys

    from helpers.gltf_writer import Gltf

    doc = Gltf()
    doc.node(doc.mesh(doc.primitive(TET_VERTICES, TET_FACES)))
    glb = doc.save(tmp_path / "t.glb")
    package(tmp_path / "t.3mf", model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)]))
    code = ("import sys, p3d_cli as p3d; [p3d.props(p, output_units='mm') for p in sys.argv[1:]]; "
            "print(sorted(m for m in ('trimesh', 'collada', 'lxml', 'networkx') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code, str(glb), str(tmp_path / "t.3mf")], capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_other_extension_geometry_and_encryption_are_refused(tmp_path):
    boolean = ('<object id="3" type="model"><bo:booleanshape objectid="1" operation="difference">'
               '<bo:boolean objectid="2"/></bo:booleanshape></object>')
    ns = ' xmlns:bo="http://schemas.3mf.io/3dmanufacturing/booleanoperations/2023/07"'
    root = model([mesh_object(1, CUBE_VERTICES, CUBE_FACES), mesh_object(2, TET_VERTICES, TET_FACES), boolean],
                 [(3, None, None)], namespaces=ns)
    with pytest.raises(FormatError, match="boolean shape"):
        p3d.props(package(tmp_path / "bool.3mf", root))
    ns = ' xmlns:sc="http://schemas.microsoft.com/3dmanufacturing/securecontent/2019/04"'
    secure = model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)], required="sc", namespaces=ns)
    with pytest.raises(FormatError, match="Secure Content"):
        p3d.props(package(tmp_path / "secure.3mf", secure))


def test_low_resolution_meshes_and_mixed_units_are_said(tmp_path):
    ns = ' xmlns:s="http://schemas.microsoft.com/3dmanufacturing/slice/2015/07"'
    lowres = mesh_object(5, TET_VERTICES, TET_FACES).replace('type="model"', 'type="model" s:meshresolution="lowres"')
    external = model([lowres], [], unit="inch", namespaces=ns)
    root = model([], [(5, None, "/3D/low.model")])
    result = p3d.props(package(tmp_path / "low.3mf", root, {"3D/low.model": external}), output_units="mm")
    assert any("low resolution" in w for w in result.warnings)
    assert any("different units (inch, millimeter)" in w for w in result.warnings)
    assert_exact(result, placed(TET_VERTICES, TET_FACES))   # the root part's millimetres


def test_a_forged_fast_mark_is_an_ordinary_attribute(tmp_path, path_kind):
    """The fast road marks the lists it read with an attribute; a file that carries that
    attribute itself gets the careful road, and the attribute means nothing."""
    tet = mesh_object(1, TET_VERTICES, TET_FACES).replace("<vertices>", '<vertices p3d-block="0">')
    cube = mesh_object(2, CUBE_VERTICES, CUBE_FACES)
    result = p3d.props(package(tmp_path / "forged.3mf", model([cube, tet], [(1, None, None)])), output_units="mm")
    assert_exact(result, placed(TET_VERTICES, TET_FACES))
