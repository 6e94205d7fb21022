"""AMF: objects of several volumes, nested constellations, units, zipped files; and hostile files
(instance bombs, zip bombs, indices that are no index), each one clear error."""

from __future__ import annotations

import io
import math
import zipfile

import numpy as np
import pytest

import p3d_cli as p3d
from helpers.exact import exact_moments
from p3d_cli.errors import FormatError

TET_V = np.array([[0.5, 0.25, -1.0], [3.0, 0.5, -0.75], [0.25, 2.0, -1.0], [0.75, 0.5, 4.0]])
TET_F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


def obj(oid: str, vertices=TET_V, volumes=(TET_F,), name: str = "tet") -> str:
    vs = "".join(f"<vertex><coordinates><x>{x}</x><y>{y}</y><z>{z}</z></coordinates></vertex>"
                 for x, y, z in np.asarray(vertices, dtype=float).tolist())
    body = "".join(f'<volume materialid="{k + 1}">' + "".join(
        f"<triangle><v1>{a}</v1><v2>{b}</v2><v3>{c}</v3></triangle>" for a, b, c in faces) + "</volume>"
        for k, faces in enumerate(volumes))
    return f'<object id="{oid}"><metadata type="name">{name}</metadata><mesh><vertices>{vs}</vertices>{body}</mesh></object>'


def amf(body: str, unit: str = "millimeter") -> str:
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<amf unit="{unit}" version="1.1">{body}</amf>'


def inst(target: str, **values) -> str:
    return f'<instance objectid="{target}">' + "".join(f"<{k}>{v}</{k}>" for k, v in values.items()) + "</instance>"


def rot(axis: str, degrees: float) -> np.ndarray:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    m = np.eye(4)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def move(x=0.0, y=0.0, z=0.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = [x, y, z]
    return m


def place(matrix) -> np.ndarray:
    return (TET_V @ matrix[:3, :3].T + matrix[:3, 3])[TET_F]


def assert_exact(result, tri, factor):
    exact = exact_moments(tri)
    assert result.properties.volume == pytest.approx(float(exact.volume) * factor ** 3, rel=1e-12)
    np.testing.assert_allclose(result.properties.center_of_mass, exact.center_float() * factor, rtol=1e-11)
    np.testing.assert_allclose(result.properties.inertia, exact.inertia() * factor ** 5, rtol=1e-9,
                               atol=1e-10 * np.abs(exact.inertia()).max() * factor ** 5)


def test_an_object_of_two_volumes_is_one_closed_mesh(tmp_path):
    path = tmp_path / "two.amf"
    path.write_text(amf(obj("1", volumes=(TET_F[:2], TET_F[2:])), "meter"))
    result = p3d.props(path)
    assert result.facts.closed is True and not result.parts
    assert_exact(result, TET_V[TET_F], 1.0)


def test_nested_constellations_with_turns_and_deltas_in_feet(tmp_path):
    inner = '<constellation id="10">' + inst("1", deltax=2, rz=30) + inst("1", deltaz=-1, rx=45, ry=10) + \
        "</constellation>"
    outer = '<constellation id="11">' + inst("10", deltay=5, rz=90) + inst("1", deltax=-7) + "</constellation>"
    path = tmp_path / "nest.amf"
    path.write_text(amf(obj("1") + inner + outer, "feet"))
    result = p3d.props(path)
    top = move(y=5) @ rot("z", 90)
    expected = [top @ move(x=2) @ rot("z", 30), top @ move(z=-1) @ rot("z", 0) @ rot("y", 10) @ rot("x", 45),
                move(x=-7)]
    assert result.details["objects"] == "3 instances" and result.units["mesh_length"] == "ft"
    for part, matrix in zip(result.parts, expected):
        assert_exact(part, place(matrix), 0.3048)


def test_zipped_amf_in_microns(tmp_path):
    path = tmp_path / "z.amf"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("model.amf", amf(obj("1"), "micron"))
    assert_exact(p3d.props(path), TET_V[TET_F], 1e-6)


def test_instance_bomb_is_refused_before_placing(tmp_path):
    """A 3 KB AMF of 26 constellations each instancing the next twice: 2^26 instances."""
    body = obj("0", name="t") + '<constellation id="c0">' + inst("0") + "</constellation>"
    for k in range(1, 27):
        body += f'<constellation id="c{k}">' + inst(f"c{k - 1}") + inst(f"c{k - 1}") + "</constellation>"
    path = tmp_path / "bomb.amf"
    path.write_text(amf(body))
    assert path.stat().st_size < 4000
    with pytest.raises(FormatError, match="67,108,864 mesh instances"):
        p3d.props(path)


def test_deep_constellation_chain_needs_no_recursion(tmp_path):
    depth = 5000
    body = obj("0") + '<constellation id="c0">' + inst("0") + "</constellation>"
    body += "".join(f'<constellation id="c{k}">' + inst(f"c{k - 1}", deltax=1) + "</constellation>"
                    for k in range(1, depth))
    path = tmp_path / "deep.amf"
    path.write_text(amf(body, "meter"))
    assert_exact(p3d.props(path), place(move(x=depth - 1)), 1.0)


def test_zip_bomb_is_refused_by_its_declared_size(tmp_path, monkeypatch):
    """The 2 MB -> 4 GB zipped AMF, scaled down: 4 MB of model under a 1 MB limit."""
    from p3d_cli.io import limits

    monkeypatch.setattr(limits, "MAX_INFLATED", 1 << 20)
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("bomb.amf", amf(obj("1")) + " " * (4 << 20))
    path = tmp_path / "bomb.amf"
    path.write_bytes(buffer.getvalue())
    assert path.stat().st_size < 20_000
    with pytest.raises(FormatError, match="more than p3d inflates"):
        p3d.props(path)


def test_zip_member_larger_than_it_declares_is_refused(tmp_path):
    buffer = io.BytesIO()
    with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
        archive.writestr("m.amf", amf(obj("1")) + " " * 100_000)
    data = bytearray(buffer.getvalue())
    # Make the member declare 1,000 bytes, in the local header and the central directory.
    for header, offset in ((b"PK\x03\x04", 22), (b"PK\x01\x02", 24)):
        at = data.find(header)
        data[at + offset:at + offset + 4] = (1000).to_bytes(4, "little")
    path = tmp_path / "liar.amf"
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="zipped AMF"):
        p3d.props(path)


@pytest.mark.parametrize("bad, words", [("1e20", "not an index"), ("nan", "not an index"), ("-1", "outside 0..2"),
                                        ("99999999999999999999999", "outside 0..2"), ("7", "refers to vertex 7"),
                                        ("1 2", "more than one index")])
def test_indices_that_are_no_index(tmp_path, bad, words):
    text = amf(obj("1")).replace("<v3>1</v3>", f"<v3>{bad}</v3>", 1)
    path = tmp_path / "bad.amf"
    path.write_text(text)
    with pytest.raises(FormatError, match=words):
        p3d.props(path)


@pytest.mark.parametrize("body, words", [
    ('<constellation id="a">' + inst("b") + '</constellation><constellation id="b">' + inst("a") + "</constellation>",
     "cycle of instances"),
    ('<constellation id="a">' + inst("9") + "</constellation>", "which the file lacks"),
    ('<constellation id="a">' + inst("1", deltax="nan") + "</constellation>", "not finite"),
])
def test_constellation_errors(tmp_path, body, words):
    path = tmp_path / "bad.amf"
    path.write_text(amf(obj("1") + body))
    with pytest.raises(FormatError, match=words):
        p3d.props(path)


@pytest.mark.parametrize("body, words", [("", "holds no <object>"),
                                         ('<object id="1"><mesh><vertices/></mesh></object>', "hold no <triangle>")])
def test_no_triangles_says_what_is_missing(tmp_path, body, words):
    from p3d_cli.errors import InputError

    path = tmp_path / "empty.amf"
    path.write_text(amf(body))
    with pytest.raises(InputError, match=words):
        p3d.props(path)
