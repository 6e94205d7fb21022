"""Hostile 3MF (issue 27): bombs made small by lowering the documented limits (a bound that
trips at 1 MB trips at 1 GB), cycles, broken references and damaged packages: each one
``p3d: error:`` line and status 2."""

from __future__ import annotations

import struct
import zipfile

import numpy as np
import pytest
from click.testing import CliRunner
from helpers.cli_errors import one_error
from helpers.gltf_writer import CUBE_FACES, CUBE_VERTICES, TET_FACES, TET_VERTICES, trs
from helpers.threemf_writer import component_object, mesh_object, model, package

from p3d_cli.cli.main import cli
from p3d_cli.io import limits
from p3d_cli.io.threemf import model as threemf_model


def tet_model(**kwargs) -> str:
    return model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)], **kwargs)


def test_inflation_past_the_limit_is_refused_before_inflating(tmp_path, monkeypatch):
    """A deflate bomb made small: a 2 MB model part (of comment-free whitespace, which deflates
    ~1000:1) against a limit of 1 MB."""
    monkeypatch.setattr(limits, "MAX_INFLATED", 1 << 20)
    text = tet_model().replace("<build>", " " * (2 << 20) + "<build>")
    path = package(tmp_path / "bomb.3mf", text)
    assert path.stat().st_size < 20_000
    one_error(path, "more than p3d inflates (1,048,576 bytes)")


def test_part_that_inflates_past_its_declared_size(tmp_path):
    """The zip says 600 bytes; the deflate stream holds far more. Stopped at the declared size."""
    text = tet_model()
    path = package(tmp_path / "liar.3mf", text)
    data = bytearray(path.read_bytes())
    name = b"3D/3dmodel.model"
    # Rewrite the declared (uncompressed) size in the local header and the central directory.
    for signature, offset in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        start = 0
        while (start := data.find(signature, start)) >= 0:
            name_at = start + (30 if signature == b"PK\x03\x04" else 46)
            if data[name_at:name_at + len(name)] == name:
                struct.pack_into("<I", data, start + offset, 600)
            start += 4
    path.write_bytes(bytes(data))
    one_error(path, "liar.3mf")


def test_component_bomb_is_refused_before_expansion(tmp_path, monkeypatch):
    """Billion laughs in components made small: 10^4 cubes (120,000 triangles) in four levels
    against a limit of 100,000 placed triangles; counted, not expanded."""
    monkeypatch.setattr(limits, "MAX_PLACED_FACES", 100_000)
    objects = [mesh_object(1, CUBE_VERTICES, CUBE_FACES)]
    for level in range(2, 6):
        objects.append(component_object(level, [(level - 1, trs((float(i), 0.0, 0.0)), None) for i in range(10)]))
    one_error(package(tmp_path / "laughs.3mf", model(objects, [(5, None, None)])), "120,000 triangles")


def test_component_cycle_and_depth(tmp_path, monkeypatch):
    cycle = model([component_object(1, [(2, None, None)]), component_object(2, [(1, None, None)])], [(1, None, None)])
    one_error(package(tmp_path / "cycle.3mf", cycle), "cycle")
    itself = model([component_object(1, [(1, None, None)])], [(1, None, None)])
    one_error(package(tmp_path / "self.3mf", itself), "cycle")
    monkeypatch.setattr(limits, "NESTING_DEPTH", 50)
    chain = [mesh_object(1, TET_VERTICES, TET_FACES)]
    chain += [component_object(i, [(i - 1, None, None)]) for i in range(2, 60)]
    one_error(package(tmp_path / "deep.3mf", model(chain, [(59, None, None)])), "deeper than p3d follows (50)")


def test_a_deep_valid_chain_is_measured_without_recursion(tmp_path):
    chain = [mesh_object(1, TET_VERTICES, TET_FACES)]
    chain += [component_object(i, [(i - 1, trs((0.001, 0.0, 0.0)), None)]) for i in range(2, 901)]
    run = CliRunner().invoke(cli, ["props", str(package(tmp_path / "rope.3mf", model(chain, [(900, None, None)]))),
                                   "--field", "volume", "--output-units", "mm"])
    assert run.exit_code == 0 and float(run.output.split()[-1]) == pytest.approx(5.0, rel=1e-12), run.output


CASES = {
    "missing object": (model([mesh_object(1, TET_VERTICES, TET_FACES)], [(7, None, None)]), "names object '7'"),
    "missing part": (model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, "/3D/none.model")]),
                     "lacks the part '3D/none.model'"),
    "index out of range": (model([mesh_object(1, TET_VERTICES, [[0, 1, 9]])], [(1, None, None)]), "outside 0..3"),
    "index 1e20": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace('v3="1"', 'v3="1e20"')],
                         [(1, None, None)]), "not a number"),
    "nan vertex": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace('x="3.0"', 'x="nan"')], [(1, None, None)]),
                   "NaN"),
    "negative index": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace('v1="1"', 'v1="-1"')],
                             [(1, None, None)]), "outside"),
    "empty coordinate": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace('y="2.0"', 'y=""')],
                               [(1, None, None)]), "not a number"),
    "two numbers in one": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace('y="2.0"', 'y="2 3"')],
                                 [(1, None, None)]), "not a number"),
    "missing attribute": (model([mesh_object(1, TET_VERTICES, TET_FACES).replace(' z="5.0"', "")],
                                [(1, None, None)]), "lacks its z attribute"),
    "bad transform": (model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)]).replace(
        'objectid="1"', 'objectid="1" transform="1 0 0 0 1 0 0 0 1 0 0"'), "12 finite numbers"),
    "infinite transform": (model([mesh_object(1, TET_VERTICES, TET_FACES)], [(1, None, None)]).replace(
        'objectid="1"', 'objectid="1" transform="1e400 0 0 0 1 0 0 0 1 0 0 0"'), "12 finite numbers"),
    "unknown unit": (tet_model(unit="furlong"), "declares unit 'furlong'"),
    "doctype entity bomb": ('<?xml version="1.0"?><!DOCTYPE model [<!ENTITY a "aaaaaaaaaa">'
                            '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>' + tet_model().split("?>", 1)[1],
                            "DOCTYPE"),
    "not xml": ("<model><resources>", "not well-formed XML"),
    "not a 3mf model": ('<model xmlns="http://example.com/other"><resources/><build><item objectid="1"/></build>'
                        "</model>", "is not a 3MF model"),
    "duplicate id": (model([mesh_object(1, TET_VERTICES, TET_FACES), mesh_object(1, TET_VERTICES, TET_FACES)],
                           [(1, None, None)]), "used twice"),
    "vertices outside an object": ('<model xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">'
                                   "<vertices/></model>", "outside an object"),
}


@pytest.mark.parametrize("streamed", [False, True])
@pytest.mark.parametrize("name", sorted(CASES))
def test_damaged_model_is_one_error(tmp_path, monkeypatch, name, streamed):
    if streamed:   # the road of parts over FAST_PART_BYTES
        monkeypatch.setattr(threemf_model, "FAST_PART_BYTES", 0)
    text, match = CASES[name]
    one_error(package(tmp_path / "bad.3mf", text), match)


def test_non_root_part_naming_another_part_is_refused(tmp_path):
    """Production extension §3.2: only the root model's components may carry p:path."""
    inner = model([component_object(3, [(4, None, "/3D/c.model")])], [])
    leaf = model([mesh_object(4, TET_VERTICES, TET_FACES)], [])
    root = model([], [(3, None, "/3D/b.model")])
    path = package(tmp_path / "chain.3mf", root, {"3D/b.model": inner, "3D/c.model": leaf})
    one_error(path, "only the root model's components may")


def test_bzip2_member_is_refused(tmp_path):
    path = package(tmp_path / "bz.3mf", tet_model(), compression=zipfile.ZIP_BZIP2)
    one_error(path, "only store and deflate")


@pytest.mark.parametrize("data", [b"PK\x03\x04" + bytes(40), b"PK" + np.random.default_rng(3).bytes(300)])
def test_not_a_zip(tmp_path, data):
    path = tmp_path / "junk.3mf"
    path.write_bytes(data)
    one_error(path, "junk.3mf")


def test_no_model_part(tmp_path):
    path = tmp_path / "empty.3mf"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("readme.txt", "nothing")
    one_error(path, "no 3D model part")
