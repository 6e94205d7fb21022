"""The OFF reader: header variants, comments and blank lines, polygons, colours, strict errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from helpers.real_meshes import check_reference
from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import load_mesh
import p3d_cli as p3d

CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_QUADS = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]


def cube_off(header=None, vertex_extra="", face_extra="", faces=CUBE_QUADS) -> str:
    text = header if header is not None else f"OFF\n8 {len(faces)} 12\n"
    text += "".join(f"{x} {y} {z}{vertex_extra}\n" for x, y, z in CUBE_V)
    text += "".join(f"{len(f)} " + " ".join(map(str, f)) + f"{face_extra}\n" for f in faces)
    return text


def write(tmp_path: Path, text: str, name="m.off") -> str:
    path = tmp_path / name
    path.write_bytes(text.encode())
    return str(path)


def expected_triangles(faces=CUBE_QUADS) -> np.ndarray:
    v = np.array(CUBE_V, dtype=float)
    return np.array([v[[f[0], f[i], f[i + 1]]] for f in faces for i in range(1, len(f) - 1)])


@pytest.mark.parametrize("text", [
    cube_off(),
    cube_off(header="OFF 8 6 12\n"),
    cube_off(header="# made by hand\nOFF\n\n# counts next\n8 6 0\n\n"),
    cube_off(header="COFF\n8 6 12\n", vertex_extra=" 255 0 0 255", face_extra=" 0.5 0.5 0.5"),
    cube_off(header="NOFF\n8 6 12\n", vertex_extra=" 0 0 1"),
    cube_off(header="CNOFF 8 6\n", vertex_extra=" 0 0 1 0.1 0.2 0.3 1.0", face_extra=" 255 0 0"),
    cube_off(header="STOFF\n8 6 12\n", vertex_extra=" 0.25 0.75"),
    cube_off().replace("\n", "\r\n"),
    cube_off().replace("1 1 1\n", "1 1 1   # a comment after a vertex\n\n\n"),
])
def test_variants_read_the_same_cube(tmp_path, text):
    path = write(tmp_path, text)
    mesh = load_mesh(path)
    assert mesh.format == "off" and mesh.coordinate_dtype == "float64" and mesh.face_count == 12
    np.testing.assert_array_equal(mesh.triangles(), expected_triangles())
    props = p3d.props(path).properties
    assert props.volume == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(props.inertia, np.eye(3) / 6, rtol=0, atol=1e-15)


def test_mixed_polygons_fan_order(tmp_path):
    faces = [(0, 3, 2), (0, 2, 1)] + CUBE_QUADS[1:]
    mesh = load_mesh(write(tmp_path, cube_off(faces=faces)))
    np.testing.assert_array_equal(mesh.triangles(), expected_triangles(faces))


def test_pentagon_fan_order(tmp_path):
    # (trimesh 5.2 fails on this file with a numpy TypeError, so the fan is checked directly.)
    angles = np.linspace(0, 2 * np.pi, 5, endpoint=False)
    verts = [(float(np.cos(a)), float(np.sin(a)), 0.0) for a in angles] + [(0.0, 0.0, 1.0)]
    text = "OFF\n6 6 0\n" + "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in verts)
    text += "5 4 3 2 1 0\n" + "".join(f"3 {i} {(i + 1) % 5} 5\n" for i in range(5))
    path = write(tmp_path, text)
    ours = load_mesh(path).triangles()
    v = np.array(verts)
    assert len(ours) == 3 + 5
    np.testing.assert_array_equal(ours[:3], v[[[4, 3, 2], [4, 2, 1], [4, 1, 0]]])
    np.testing.assert_array_equal(ours[3:], np.array([v[[i, (i + 1) % 5, 5]] for i in range(5)]))
    # A closed pyramid over a regular pentagon: volume = base area * height / 3.
    area = 5 / 2 * np.sin(2 * np.pi / 5)
    assert p3d.props(path).properties.volume == pytest.approx(area / 3, rel=1e-14)


def test_decimal_text_is_float64(tmp_path):
    text = "OFF\n3 1 0\n0.1 0.2 0.3\n1e-3 2.5E+2 -0\n0.30000000000000004 1 1\n3 0 1 2\n"
    tris = load_mesh(write(tmp_path, text)).triangles()
    assert tris[0, 0].tolist() == [0.1, 0.2, 0.3] and tris[0, 2, 0] == 0.30000000000000004


def test_extra_lines_after_faces_warn(tmp_path):
    mesh = load_mesh(write(tmp_path, cube_off() + "1 2 3\n"))
    assert any("1 lines after the last face" in w for w in mesh.warnings)


# --- errors ------------------------------------------------------------------------------

def raises(tmp_path, text, kind=FormatError):
    with pytest.raises(kind) as info:
        load_mesh(write(tmp_path, text), format="off")
    assert info.value.hint
    return info.value


@pytest.mark.parametrize("header, claim", [("OFF\n9 6 12\n", "9 vertices"), ("OFF\n8 7 12\n", "7 faces"),
                                           ("OFF 8 1000000000000 0\n", "1000000000000 faces")])
def test_counts_claiming_more_than_present(tmp_path, header, claim):
    err = raises(tmp_path, cube_off(header=header))
    assert claim in err.what and "only 14 lines follow" in err.what


def test_index_out_of_range_names_line_and_index(tmp_path):
    faces = list(CUBE_QUADS)
    faces[4] = (2, 3, 9, 6)
    err = raises(tmp_path, cube_off(faces=faces))
    assert "line 15" in err.where and "face index 9" in err.what and "8 vertices" in err.what


def test_negative_index(tmp_path):
    faces = list(CUBE_QUADS)
    faces[0] = (0, -1, 2, 1)
    err = raises(tmp_path, cube_off(faces=faces))
    assert "line 11" in err.where and "-1" in err.what


@pytest.mark.parametrize("edit, line, words", [
    (lambda t: t.replace("1 1 0\n", "1 1\n"), 5, "x y z"),
    (lambda t: t.replace("1 1 0\n", "1 one 0\n"), 5, "'1 one 0'"),
    (lambda t: t.replace("4 0 3 2 1\n", "2 0 3\n"), 11, "k >= 3"),
    (lambda t: t.replace("4 0 3 2 1\n", "4 0 3 2\n"), 11, "k >= 3"),
    (lambda t: t.replace("4 0 3 2 1\n", "4 0 3 x 1\n"), 11, "'4 0 3 x 1'"),
    (lambda t: t.replace("8 6 12", "8 six 12"), 2, "counts"),
    (lambda t: t.replace("OFF", "4OFF"), 1, "not supported"),
    (lambda t: t.replace("OFF", "OFFX"), 1, "expected an 'OFF' header"),
])
def test_malformed_lines(tmp_path, edit, line, words):
    err = raises(tmp_path, edit(cube_off()))
    assert f"line {line}" in err.where and words in err.what


def test_no_faces_is_input_error(tmp_path):
    err = raises(tmp_path, cube_off(header="OFF\n8 0 0\n", faces=[]), InputError)
    assert not isinstance(err, FormatError) and "no faces" in err.what


def test_empty_after_header(tmp_path):
    err = raises(tmp_path, "OFF\n")
    assert "ends after" in err.what


# --- real meshes -------------------------------------------------------------------------

def test_real_off_matches_reference(real_meshes, reference):
    name = "euclid__kitten.off"
    path = str(real_meshes / name)
    mesh = load_mesh(path)
    ref = reference[name]
    assert mesh.format == "off" and mesh.face_count == ref["faces"]
    check_reference(p3d.props(path).properties, ref)
