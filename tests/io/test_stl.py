"""STL reading: binary (even with a 'solid' header), ASCII (several solids), and every way to fail."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl
from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import load_mesh
import p3d_cli as p3d


def test_binary_with_solid_header_is_read_as_binary(tmp_path):
    path = tmp_path / "cad.stl"
    write_binary_stl(path, cube_triangles() + 10, header=b"solid exported by a CAD tool")
    mesh = load_mesh(str(path))
    assert mesh.format == "stl-binary" and mesh.face_count == 12
    assert mesh.coordinate_dtype == "float32"
    np.testing.assert_array_equal(mesh.triangles(), (cube_triangles() + 10).astype(np.float32))


def test_binary_trailing_bytes_warn(tmp_path):
    path = tmp_path / "trail.stl"
    write_binary_stl(path, cube_triangles())
    with open(path, "ab") as f:
        f.write(b"\0" * 7)
    result = p3d.props(str(path))
    assert result.properties.volume == pytest.approx(1.0)
    assert any("7 trailing bytes" in w for w in result.warnings)


def test_binary_lying_header_fails_fast(tmp_path):
    path = tmp_path / "lie.stl"
    write_binary_stl(path, cube_triangles())
    data = bytearray(path.read_bytes())
    data[80:84] = np.uint32(4_000_000_000).tobytes()  # claims 200 GB of triangles
    path.write_bytes(bytes(data))
    with pytest.raises(FormatError, match="claims 4000000000 triangles"):
        load_mesh(str(path))


def test_binary_truncated(tmp_path):
    path = tmp_path / "cut.stl"
    write_binary_stl(path, cube_triangles())
    path.write_bytes(path.read_bytes()[:-30])
    with pytest.raises(FormatError, match="truncated"):
        load_mesh(str(path))


def test_binary_zero_triangles(tmp_path):
    path = tmp_path / "empty.stl"
    write_binary_stl(path, np.zeros((0, 3, 3)))
    with pytest.raises(InputError, match="no triangles"):
        load_mesh(str(path))


def test_too_short_for_header(tmp_path):
    path = tmp_path / "short.stl"
    path.write_bytes(b"\x01\x02\x03")
    with pytest.raises(FormatError, match="too short"):
        load_mesh(str(path))


def test_ascii_round_trip_full_precision(tmp_path):
    tri = cube_triangles() * np.pi + 1 / 3
    path = tmp_path / "a.stl"
    write_ascii_stl(path, tri)
    mesh = load_mesh(str(path))
    assert mesh.format == "stl-ascii" and mesh.coordinate_dtype == "float64"
    np.testing.assert_array_equal(mesh.triangles(), tri)


def test_ascii_several_solids_and_odd_names(tmp_path):
    a, b = cube_triangles(), cube_triangles() + [5, 0, 0]
    path = tmp_path / "two.stl"
    write_ascii_stl(path, a, name="first 1.5 2.5")
    text = path.read_text()
    write_ascii_stl(path, b, name="second")
    path.write_text(text + path.read_text().replace("\n", "\r\n"))
    result = p3d.props(str(path))
    assert result.facts.faces == 24
    assert result.properties.volume == pytest.approx(2.0, rel=1e-14)
    np.testing.assert_allclose(result.properties.center_of_mass, [3.0, 0.5, 0.5], rtol=1e-14)


def test_ascii_quad_facet_is_fanned(tmp_path):
    path = tmp_path / "quad.stl"
    path.write_text("solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                    "vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid q\n")
    tri = load_mesh(str(path)).triangles()
    np.testing.assert_array_equal(tri, [[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]])


@pytest.mark.parametrize("bad, message", [
    ("vertex 1 2\n", "line 4: expected 'vertex X Y Z'"),
    ("vertex 1 2 zz\n", "line 4: expected 'vertex X Y Z'"),
    ("wobble\n", "line 4: unexpected 'wobble'"),
])
def test_ascii_malformed_lines_name_the_line(tmp_path, bad, message):
    path = tmp_path / "bad.stl"
    path.write_text("solid b\nfacet normal 0 0 1\nouter loop\n" + bad + "endloop\nendfacet\nendsolid b\n")
    with pytest.raises(FormatError, match=message):
        load_mesh(str(path))


def test_ascii_truncated_inside_facet(tmp_path):
    path = tmp_path / "cut.stl"
    path.write_text("solid b\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n")
    with pytest.raises(FormatError, match="ends inside a facet"):
        load_mesh(str(path))


def test_ascii_without_facets(tmp_path):
    path = tmp_path / "none.stl"
    path.write_text("solid nothing\nendsolid nothing\n")
    with pytest.raises(InputError, match="no facets"):
        load_mesh(str(path))


def test_nan_coordinate_names_the_face(tmp_path):
    tri = cube_triangles()
    tri[5, 1, 2] = np.nan
    path = tmp_path / "nan.stl"
    write_binary_stl(path, tri)
    with pytest.raises(InputError, match="face 5 has a NaN or infinite coordinate"):
        p3d.props(str(path))


def test_stdin_is_read(tmp_path):
    import io

    path = tmp_path / "c.stl"
    write_binary_stl(path, cube_triangles())
    result = p3d.props("-", stdin=io.BytesIO(path.read_bytes()))
    assert result.properties.volume == pytest.approx(1.0)
    assert result.facts.format == "stl-binary"


def test_off_variants_are_recognised_by_content_on_stdin():
    """Standard input has no extension: an OFF header after comments, or a variant keyword
    (COFF with colours), must still be recognised from the content."""
    import io as _io

    points = ["0 0 0", "1 0 0", "0 1 0", "0 0 1"]
    faces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n"
    plain = "4 4 0\n" + "\n".join(points) + "\n" + faces
    coloured = "4 4 0\n" + "\n".join(p + " 255 0 0 255" for p in points) + "\n" + faces
    for text in ("OFF\n" + plain, "# made by hand\n\nOFF\n" + plain, "COFF\n" + coloured):
        result = p3d.props("-", stdin=_io.BytesIO(text.encode()))
        assert result.facts.format == "off", text[:20]
        assert result.properties.volume == pytest.approx(1 / 6), text[:20]


NONSTANDARD = """solid STL generated by MeshLab
  facet normal  0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 2 0
      vertex 2 0 0
    endloop
  endfacet
  facet normal +inf  -inf  weirdvalue
    outer loop
      vertex 0 0 0
      vertex 2 0 0
      vertex 0 0 2
    endloop foo
  endfacet bar
  facet normal
    outer loop
      vertex 0 0 0
      vertex 0 0 2
      vertex 0 2 0
    endloop
  endfacet blah
  facet
    outer loop
      vertex 2 0 0
      vertex 0 2 0
      vertex 0 0 2
    endloop
  endfacet
endsolid some blah blah
"""


def test_a_facet_normal_that_is_not_numbers_is_not_read(tmp_path):
    """PrusaSlicer's 20mmbox-nonstandard.stl holds 'facet normal +inf -inf weirdvalue' and words
    after endloop and endfacet: the normal is never used, and such files were read before."""
    path = tmp_path / "nonstandard.stl"
    path.write_text(NONSTANDARD)
    result = p3d.props(path)
    assert result.properties.volume == pytest.approx(8 / 6, rel=1e-15) and result.facts.closed
    assert p3d.check(path).ok
