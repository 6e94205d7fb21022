"""glTF/GLB, 3MF, COLLADA and AMF: scene graphs and declared units against exact integrals.

Every file is written here (trimesh exports glTF, GLB and 3MF; DAE and AMF are written as
text), with node transforms and units that change the answer. The oracle is ``exact.py``: the
exact rational integrals of the same triangles, placed by the same matrices, then carried to
SI by the file's unit (a length factor f: volume f³, centre f, inertia f⁵).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner
from helpers.exact import exact_moments

import p3d_cli as p3d
from p3d_cli.cli.main import cli
from p3d_cli.errors import UsageError
from p3d_cli.geometry.placement import Placement
from p3d_cli.measure.assembly.parts import Assembly, Part

RTOL = 1e-12


def rotation_z(degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def matrix(scale=1.0, rotation=None, translation=(0.0, 0.0, 0.0)) -> np.ndarray:
    out = np.eye(4)
    out[:3, :3] = (np.eye(3) if rotation is None else rotation) * scale
    out[:3, 3] = translation
    return out


#: An irregular closed solid (a perturbed icosphere) and a box off the origin, in float32.
BLOB = trimesh.creation.icosphere(1, radius=0.7)
BLOB.vertices = (BLOB.vertices * [1.0, 0.8, 1.3] + [0.2, -0.1, 0.05]).astype(np.float32).astype(np.float64)
BOX = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
BOX.vertices = (BOX.vertices + [0.25, 0.5, 1.0]).astype(np.float32).astype(np.float64)

#: Node transforms: a node scaled by 0.001 and rotated; a node translated.
NODE_A = matrix(0.001, rotation_z(30.0), (0.01, 0.02, -0.03))
NODE_B = matrix(1.0, None, (2.0, 0.0, 1.0))


def placed(mesh, transform) -> np.ndarray:
    """The mesh's triangles through ``transform``, computed in float64 as the reader does."""
    vertices = np.asarray(mesh.vertices, dtype=np.float64) @ transform[:3, :3].T + transform[:3, 3]
    return vertices[np.asarray(mesh.faces)]


def assert_exact(result, triangles, factor=1.0):
    """``result`` equals the exact integrals of ``triangles`` scaled by ``factor``."""
    exact = exact_moments(triangles)
    p = result.properties
    assert p.volume == pytest.approx(float(exact.volume) * factor ** 3, rel=RTOL)
    np.testing.assert_allclose(p.center_of_mass, exact.center_float() * factor, rtol=RTOL,
                               atol=RTOL * np.abs(exact.center_float()).max() * factor)
    inertia = exact.inertia() * factor ** 5
    np.testing.assert_allclose(p.inertia, inertia, rtol=1e-10, atol=1e-10 * np.abs(inertia).max())


def scene(*entries) -> trimesh.Scene:
    out = trimesh.Scene()
    for name, mesh, transform in entries:
        out.add_geometry(mesh, node_name=name, geom_name=name + "-mesh", transform=transform)
    return out


@pytest.fixture
def glb(tmp_path):
    path = tmp_path / "two.glb"
    path.write_bytes(scene(("blob", BLOB, NODE_A), ("box", BOX, NODE_B)).export(file_type="glb"))
    return path


@pytest.mark.parametrize("kind", ["glb", "gltf"])
def test_gltf_nodes_are_placed_and_in_metres(tmp_path, kind):
    out = scene(("blob", BLOB, NODE_A), ("box", BOX, NODE_B)).export(file_type=kind)
    if kind == "gltf":
        for name, data in out.items():
            (tmp_path / name).write_bytes(data)
        path = tmp_path / "model.gltf"
    else:
        path = tmp_path / "two.glb"
        path.write_bytes(out)
    result = p3d.props(path)
    assert result.facts.format == "gltf" and result.details["objects"] == "2 nodes"
    assert result.units["mesh_length"] == "m" and result.units["system"] == "SI"
    parts = {part.details["name"]: part for part in result.parts}
    assert_exact(parts["blob"], placed(BLOB, NODE_A))
    assert_exact(parts["box"], placed(BOX, NODE_B))
    assert_exact(result, np.concatenate([placed(BLOB, NODE_A), placed(BOX, NODE_B)]))
    assert result.facts.faces == len(BLOB.faces) + len(BOX.faces)


def test_multi_object_glb_equals_the_assembly_of_its_parts(glb):
    """The same parts as an assembly (STL-like arrays, placed by Placement) give the same whole."""
    parts = (Part("blob", (BLOB.vertices, BLOB.faces), Placement(np.full(3, 0.001), rotation_z(30.0), NODE_A[:3, 3])),
             Part("box", (BOX.vertices, BOX.faces), Placement(None, None, NODE_B[:3, 3])))
    expected = p3d.props(Assembly("by-hand", parts, "m"), density="1000kg/m^3")
    got = p3d.props(glb, density="1000kg/m^3")
    assert [p.details["name"] for p in got.parts] == ["blob", "box"]
    for a, b in [(got, expected)] + list(zip(got.parts, expected.parts)):
        assert a.properties.mass == pytest.approx(b.properties.mass, rel=RTOL)
        np.testing.assert_allclose(a.properties.center_of_mass, b.properties.center_of_mass, rtol=1e-11)
        np.testing.assert_allclose(a.properties.inertia, b.properties.inertia, rtol=1e-10,
                                   atol=1e-12 * np.abs(b.properties.inertia).max())


def test_3mf_in_millimetres_with_build_items(tmp_path):
    path = tmp_path / "plate.3mf"
    path.write_bytes(scene(("blob", BLOB, NODE_A), ("box", BOX, NODE_B)).export(file_type="3mf"))
    result = p3d.props(path)
    assert result.facts.format == "3mf" and result.details["objects"] == "2 objects (build items and their components)"
    assert result.units["mesh_length"] == "mm"
    # trimesh writes the vertices as decimal text of the float64 values; the unit makes 1e-3.
    parts = {part.details["name"]: part for part in result.parts}
    assert_exact(parts["box"], placed(BOX, NODE_B), 1e-3)
    whole = p3d.props(path, output_units="mm,g")
    assert_exact(whole, np.concatenate([placed(BLOB, NODE_A), placed(BOX, NODE_B)]))


def test_single_object_3mf_is_no_assembly(tmp_path):
    path = tmp_path / "one.3mf"
    path.write_bytes(scene(("box", BOX, NODE_B)).export(file_type="3mf"))
    result = p3d.props(path, output_units="mm,g")
    assert not result.parts and "objects" not in result.details
    assert_exact(result, placed(BOX, NODE_B))


TET = "0 0 0 3 0 0 0 2 0 0 0 5"
TET_FACES = "0 2 1 0 1 3 0 3 2 1 2 3"


def dae(meter: str, nodes: str) -> str:
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="u" meter="{meter}"/><up_axis>Z_UP</up_axis></asset>
  <library_geometries><geometry id="tet" name="tet"><mesh>
    <source id="pos"><float_array id="pos-a" count="12">{TET}</float_array>
      <technique_common><accessor source="#pos-a" count="4" stride="3"><param name="X" type="float"/>
      <param name="Y" type="float"/><param name="Z" type="float"/></accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#pos"/></vertices>
    <triangles count="4"><input semantic="VERTEX" source="#v" offset="0"/><p>{TET_FACES}</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s">{nodes}</visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def tet_triangles(transform=np.eye(4)) -> np.ndarray:
    vertices = np.array(TET.split(), dtype=np.float64).reshape(-1, 3)
    faces = np.array(TET_FACES.split(), dtype=np.int64).reshape(-1, 3)
    return (vertices @ transform[:3, :3].T + transform[:3, 3])[faces]


def test_dae_in_inches_with_nested_node_transforms(tmp_path):
    # A quarter turn about z as an exact <matrix> (pycollada parses COLLADA floats as float32,
    # so a <rotate> by 90 degrees would carry cos(90°) rounded in float32), inside a translated,
    # scaled parent.
    nodes = ('<node id="a" name="a"><translate>1 2 3</translate><scale>2 2 2</scale>'
             '<node id="b" name="b"><matrix>0 -1 0 0 1 0 0 0 0 0 1 0 0 0 0 1</matrix>'
             '<instance_geometry url="#tet"/></node></node>')
    path = tmp_path / "link.dae"
    path.write_text(dae("0.0254", nodes))
    result = p3d.props(path)
    assert result.facts.format == "dae" and result.units["mesh_length"] == "in" and not result.parts
    quarter = matrix(1.0, np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]))
    whole = matrix(2.0, None, (1.0, 2.0, 3.0)) @ quarter
    assert_exact(result, tet_triangles(whole), 0.0254)


def test_dae_unit_outside_the_table_is_folded_into_metres(tmp_path):
    path = tmp_path / "half.dae"
    path.write_text(dae("0.5", '<node id="a"><instance_geometry url="#tet"/></node>'))
    result = p3d.props(path)
    assert result.units["mesh_length"] == "m"
    assert_exact(result, tet_triangles(), 0.5)


AMF = """<?xml version="1.0" encoding="UTF-8"?>
<amf unit="inch" version="1.1">
  <object id="7"><metadata type="name">tet</metadata><mesh><vertices>{vertices}</vertices>
    <volume>{triangles}</volume></mesh></object>
  <constellation id="1"><instance objectid="7"><deltax>10</deltax><rz>90</rz></instance>
    <instance objectid="7"><deltay>-4</deltay></instance></constellation>
</amf>"""


def amf_text() -> str:
    vs = np.array(TET.split(), dtype=float).reshape(-1, 3)
    fs = np.array(TET_FACES.split(), dtype=int).reshape(-1, 3)
    vertices = "".join(f"<vertex><coordinates><x>{x}</x><y>{y}</y><z>{z}</z></coordinates></vertex>"
                       for x, y, z in vs)
    triangles = "".join(f"<triangle><v1>{a}</v1><v2>{b}</v2><v3>{c}</v3></triangle>" for a, b, c in fs)
    return AMF.format(vertices=vertices, triangles=triangles)


@pytest.mark.parametrize("zipped", [False, True])
def test_amf_constellation_in_inches(tmp_path, zipped):
    import zipfile

    path = tmp_path / "pair.amf"
    if zipped:
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
            archive.writestr("pair.amf", amf_text())
    else:
        path.write_text(amf_text())
    result = p3d.props(path)
    assert result.details["objects"] == "2 instances" and [p.details["name"] for p in result.parts] == ["tet", "tet-2"]
    turned = matrix(1.0, np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]), (10.0, 0.0, 0.0))
    assert_exact(result.parts[0], tet_triangles(turned), 0.0254)
    assert_exact(result.parts[1], tet_triangles(matrix(1.0, None, (0.0, -4.0, 0.0))), 0.0254)
    assert_exact(result, np.concatenate([tet_triangles(turned), tet_triangles(matrix(1.0, None, (0, -4, 0)))]),
                 0.0254)


def test_mirroring_node_keeps_the_solid_outward(tmp_path):
    mirror = np.diag([-1.0, 1.0, 1.0, 1.0])
    path = tmp_path / "mirror.glb"
    path.write_bytes(scene(("blob", BLOB, mirror)).export(file_type="glb"))
    result = p3d.props(path)
    assert result.properties.volume > 0 and result.facts.closed
    assert_exact(result, placed(BLOB, mirror)[:, ::-1])


def test_round_trip_of_one_mesh_through_six_formats(tmp_path):
    """The same triangles saved as STL, OBJ, PLY, DAE, GLB and 3MF measure the same (to the
    float32 storage of STL, GLB and DAE: a relative 1e-7)."""
    mesh = BLOB.copy()
    for ext in ("stl", "obj", "ply", "dae", "glb", "3mf"):
        mesh.export(tmp_path / f"blob.{ext}")
    reference = p3d.props(tmp_path / "blob.ply", units="m")
    for ext in ("stl", "obj", "dae", "glb"):
        got = p3d.props(tmp_path / f"blob.{ext}", units="m")
        assert got.properties.volume == pytest.approx(reference.properties.volume, rel=1e-6), ext
        np.testing.assert_allclose(got.properties.inertia, reference.properties.inertia, rtol=1e-5,
                                   atol=1e-6 * np.abs(reference.properties.inertia).max(), err_msg=ext)
        assert got.facts.faces == len(mesh.faces)
    # trimesh writes 3MF in millimetres: the same numbers, a thousand times smaller in SI.
    mm = p3d.props(tmp_path / "blob.3mf", output_units="mm,kg")
    assert mm.properties.volume == pytest.approx(reference.properties.volume, rel=1e-6)


def test_check_checks_each_object_and_the_whole(tmp_path):
    open_box = BOX.copy()
    open_box.faces = open_box.faces[1:]
    path = tmp_path / "two.glb"
    path.write_bytes(scene(("blob", BLOB, NODE_A), ("lid", open_box, NODE_B)).export(file_type="glb"))
    result = p3d.check(path)
    names = [name for name, _ in result.parts]
    assert names == ["blob", "lid"] and result.parts[0][1].ok and not result.parts[1][1].ok
    assert not result.ok and "lid:closed" in result.failed and "closed" in result.failed
    record = json.loads(CliRunner().invoke(cli, ["check", str(path), "--json"]).output)
    assert [p["name"] for p in record["parts"]] == ["blob", "lid"] and record["parts"][1]["ok"] is False


def test_cli_json_lists_objects_like_an_assembly(glb):
    run = CliRunner().invoke(cli, ["props", str(glb), "--json", "--density", "1g/cm^3"])
    assert run.exit_code == 0, run.output
    record = json.loads(run.output)
    assert record["format"] == "gltf" and record["objects"] == "2 nodes"
    assert [p["name"] for p in record["parts"]] == ["blob", "box"]
    assert record["mass"] == pytest.approx(sum(p["mass"] for p in record["parts"]), rel=1e-14)


def test_declared_unit_rules(glb):
    with pytest.raises(UsageError, match="declares its length unit"):
        p3d.props(glb, density=1000)
    with pytest.raises(UsageError, match="declares its unit: m"):
        p3d.props(glb, units="mm")
    assert p3d.props(glb, units="m").units["mesh_length"] == "m"
    bounds = p3d.bounds(glb, output_units="mm")
    expected = np.concatenate([placed(BLOB, NODE_A), placed(BOX, NODE_B)]).reshape(-1, 3)
    np.testing.assert_allclose(bounds.bounds.max, expected.max(axis=0) * 1000, rtol=1e-12)


def test_scene_file_in_an_assembly_is_scaled_from_its_unit(tmp_path):
    """A 3MF (mm) part of an assembly in metres is converted; without units it is refused."""
    path = tmp_path / "box.3mf"
    path.write_bytes(scene(("box", BOX, np.eye(4))).export(file_type="3mf"))
    (tmp_path / "a.yaml").write_text("units: m\nparts:\n  - mesh: box.3mf\n  - shape: box:1,1,1\n")
    result = p3d.props(tmp_path / "a.yaml")
    assert result.parts[0].properties.volume == pytest.approx(6e-9, rel=1e-12)
    assert result.parts[1].properties.volume == pytest.approx(8.0, rel=1e-12)
    (tmp_path / "b.yaml").write_text("parts:\n  - mesh: box.3mf\n")
    with pytest.raises(p3d.InputError if hasattr(p3d, "InputError") else Exception, match="declares its unit"):
        p3d.props(tmp_path / "b.yaml")


def test_dae_strips_are_read(tmp_path):
    """Triangle strips were refused (trimesh's reader left them out); they are read now."""
    path = tmp_path / "strips.dae"
    path.write_text(dae("1", '<node id="a"><instance_geometry url="#tet"/></node>').replace(
        "</mesh>", '<tristrips count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>1 2 3 0</p></tristrips></mesh>'))
    strip = np.array([[1, 2, 3], [3, 2, 0]])     # the second reversed: (s1, s0, s2) of (2, 3, 0)
    vertices = np.array(TET.split(), dtype=np.float64).reshape(-1, 3)
    faces = np.concatenate([np.array(TET_FACES.split(), dtype=np.int64).reshape(-1, 3), strip])
    assert_exact(p3d.props(path), vertices[faces])


def test_dae_library_nodes_are_instanced(tmp_path):
    nodes = '<node id="n"><translate>0 0 7</translate><instance_node url="#lib"/></node>'
    text = dae("1", nodes).replace("<library_visual_scenes>", '<library_nodes><node id="lib"><scale>2 1 1</scale>'
                                   '<instance_geometry url="#tet"/></node></library_nodes><library_visual_scenes>')
    path = tmp_path / "inst.dae"
    path.write_text(text)
    result = p3d.props(path)
    assert_exact(result, tet_triangles(matrix(1.0, np.diag([2.0, 1, 1]), (0.0, 0.0, 7.0))))


def test_3mf_components_and_a_mirrored_build_item(tmp_path):
    """3MF transforms act on row vectors (p' = p M, core specification §4.1.1): a build item
    of an object made of two components (one turned and moved), and a mirrored build item."""
    import zipfile

    model = ('<?xml version="1.0" encoding="UTF-8"?><model unit="inch" '
             'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources>'
             '<object id="1" type="model" name="tet"><mesh><vertices>'
             + "".join(f'<vertex x="{x}" y="{y}" z="{z}"/>' for x, y, z in np.array(TET.split()).reshape(-1, 3))
             + "</vertices><triangles>"
             + "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in np.array(TET_FACES.split()).reshape(-1, 3))
             + '</triangles></mesh></object><object id="2" type="model" name="pair"><components>'
             '<component objectid="1"/><component objectid="1" transform="0 1 0 -1 0 0 0 0 1 10 0 0"/>'
             '</components></object></resources><build><item objectid="2" transform="1 0 0 0 1 0 0 0 1 0 0 100"/>'
             '<item objectid="1" transform="-1 0 0 0 1 0 0 0 1 0 0 0"/></build></model>')
    path = tmp_path / "pair.3mf"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("3D/3dmodel.model", model)
    result = p3d.props(path)
    assert result.units["mesh_length"] == "in" and len(result.parts) == 3
    up = matrix(1.0, None, (0.0, 0.0, 100.0))
    turned = up @ matrix(1.0, np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]), (10.0, 0.0, 0.0))
    mirrored = np.diag([-1.0, 1, 1, 1])
    assert_exact(result.parts[0], tet_triangles(up), 0.0254)
    assert_exact(result.parts[1], tet_triangles(turned), 0.0254)
    assert_exact(result.parts[2], tet_triangles(mirrored)[:, ::-1], 0.0254)
    assert all(p.properties.volume > 0 for p in result.parts)


def test_directory_of_a_robot_package(tmp_path):
    """A description package: the directory search reads the DAE and GLB meshes, skips the URDF."""
    (tmp_path / "arm.urdf").write_text('<robot name="arm"><link name="base"/></robot>')
    (tmp_path / "base.dae").write_text(dae("1", '<node id="a"><instance_geometry url="#tet"/></node>'))
    (tmp_path / "wheel.glb").write_bytes(scene(("box", BOX, NODE_B)).export(file_type="glb"))
    run = CliRunner().invoke(cli, ["props", str(tmp_path), "--json"])
    assert run.exit_code == 0, run.output
    sources = sorted(json.loads(line)["source"].rsplit("/", 1)[-1] for line in run.output.splitlines() if line.startswith("{"))
    assert sources == ["base.dae", "wheel.glb"]


@pytest.mark.parametrize("kind", ["dae", "3mf"])
def test_nothing_is_merged(tmp_path, kind):
    """A vertex 1e-9 from another stays apart (trimesh's processing would merge within 1e-8):
    the mesh is open by exact coordinates, and the integrals are of the triangles as written."""
    vertices = np.array([[0, 0, 0], [3, 0, 0], [0, 2, 0], [0, 0, 5], [1e-9, 0, 0]], dtype=np.float64)
    faces = np.array([[0, 2, 1], [0, 1, 3], [4, 3, 2], [1, 2, 3]])
    path = tmp_path / f"near.{kind}"
    if kind == "dae":   # written without normals, which would keep trimesh from merging
        text = dae("1", '<node id="a"><instance_geometry url="#tet"/></node>')
        text = text.replace(TET, " ".join(map(repr, vertices.reshape(-1).tolist()))).replace(
            'count="12"', 'count="15"').replace('count="4" stride', 'count="5" stride')
        path.write_text(text.replace(TET_FACES, " ".join(map(str, faces.reshape(-1)))))
    else:
        path.write_bytes(trimesh.Trimesh(vertices, faces, process=False).export(file_type=kind))
    result = p3d.props(path, output_units="m" if kind == "dae" else "mm")
    assert result.facts.closed is False
    assert_exact(result, vertices[faces])
