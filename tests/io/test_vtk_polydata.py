"""VTK PolyData, XML (.vtp) and legacy (.vtk POLYDATA), in every data layout, against exact integrals.

The files are written here from the VTK file formats document: ASCII, base64 binary (header
encoded with the data or apart), zlib-compressed blocks, appended raw data, legacy ASCII and
big-endian binary, classic and 5.1 cell layouts; polygons and triangle strips.
"""

from __future__ import annotations

import base64
import json
import struct
import zlib

import numpy as np
import pytest
import trimesh

import p3d_cli as p3d
from helpers.exact import exact_moments
from p3d_cli.errors import FormatError

BLOB = trimesh.creation.icosphere(1, radius=0.7)
POINTS = (BLOB.vertices * [1.0, 0.8, 1.3] + [0.2, -0.1, 0.05]).astype(np.float32)
FACES = np.asarray(BLOB.faces)
EXACT = exact_moments(POINTS[FACES])


def assert_blob(result, dtype="float32"):
    assert result.properties.volume == pytest.approx(float(EXACT.volume), rel=1e-13)
    np.testing.assert_allclose(result.properties.center_of_mass, EXACT.center_float(), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(result.properties.inertia, EXACT.inertia(), rtol=1e-11, atol=1e-14)
    assert result.facts.closed and result.facts.coordinate_dtype == dtype


def encoded(array: np.ndarray, header: str, compressed: bool, apart: bool) -> bytes:
    """One DataArray's base64 text (little-endian), as vtkXMLWriter writes it."""
    data = array.tobytes()
    h = "<I" if header == "UInt32" else "<Q"
    if compressed:
        blocks = [zlib.compress(data[i:i + 64]) for i in range(0, len(data), 64)]
        last = len(data) % 64 or 64
        head = struct.pack(h[0] + h[1] * (3 + len(blocks)), len(blocks), 64, last, *map(len, blocks))
        return base64.b64encode(head) + base64.b64encode(b"".join(blocks))
    head = struct.pack(h, len(data))
    return base64.b64encode(head) + base64.b64encode(data) if apart else base64.b64encode(head + data)


def vtp(fmt: str, header="UInt32", compressed=False, apart=False) -> bytes:
    arrays = {"points": POINTS.reshape(-1), "connectivity": FACES.reshape(-1).astype(np.int64),
              "offsets": np.arange(3, 3 * len(FACES) + 1, 3, dtype=np.int64)}
    types = {"points": "Float32", "connectivity": "Int64", "offsets": "Int64"}
    body, appended, offset = {}, b"", 0
    for name, array in arrays.items():
        if fmt == "ascii":
            body[name] = ("ascii", "", " ".join(map(repr, array.tolist())).encode())
        elif fmt == "binary":
            body[name] = ("binary", "", encoded(array, header, compressed, apart))
        else:
            raw = struct.pack("<I" if header == "UInt32" else "<Q", array.nbytes) + array.tobytes()
            body[name] = ("appended", f' offset="{offset}"', b"")
            appended += raw
            offset += len(raw)

    def data_array(name, extra=""):
        kind, off, text = body[name]
        return (f'<DataArray type="{types[name]}" Name="{name}"{extra} format="{kind}"{off}>'.encode() + text
                + b"</DataArray>")

    out = (f'<?xml version="1.0"?>\n<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
           f'header_type="{header}"' + (' compressor="vtkZLibDataCompressor"' if compressed else "") + ">"
           f'<PolyData><Piece NumberOfPoints="{len(POINTS)}" NumberOfPolys="{len(FACES)}">').encode()
    out += b"<Points>" + data_array("points", ' NumberOfComponents="3"') + b"</Points>"
    out += b"<Polys>" + data_array("connectivity") + data_array("offsets") + b"</Polys></Piece></PolyData>"
    if appended:
        out += b'<AppendedData encoding="raw">_' + appended + b"</AppendedData>"
    return out + b"</VTKFile>\n"


@pytest.mark.parametrize("fmt, header, compressed, apart", [
    ("ascii", "UInt32", False, False), ("binary", "UInt32", False, False), ("binary", "UInt32", False, True),
    ("binary", "UInt64", False, False), ("binary", "UInt32", True, False), ("binary", "UInt64", True, False),
    ("appended", "UInt32", False, False), ("appended", "UInt64", False, False)])
def test_vtp_layouts(tmp_path, fmt, header, compressed, apart):
    path = tmp_path / "blob.vtp"
    path.write_bytes(vtp(fmt, header, compressed, apart))
    result = p3d.props(path)
    assert result.facts.format == "vtp"
    assert_blob(result, "float64" if fmt == "ascii" else "float32")


def test_an_empty_header_type_is_the_default_uint32(tmp_path):
    path = tmp_path / "blob.vtp"
    path.write_bytes(vtp("binary", "UInt32", True, False).replace(b'header_type="UInt32"', b'header_type=""'))
    assert_blob(p3d.props(path), "float32")


def legacy(binary: bool, new_layout: bool, strips: bool = False) -> bytes:
    version = "5.1" if new_layout else "3.0"
    out = f"# vtk DataFile Version {version}\nblob\n{'BINARY' if binary else 'ASCII'}\nDATASET POLYDATA\n".encode()
    out += f"POINTS {len(POINTS)} float\n".encode()
    out += POINTS.astype(">f4").tobytes() + b"\n" if binary else " ".join(map(repr, POINTS.reshape(-1).tolist())).encode() + b"\n"
    cells = [list(f) for f in FACES]
    key = "POLYGONS"
    if new_layout:
        offsets = np.concatenate([[0], np.cumsum([len(c) for c in cells])]).astype(np.int64)
        connectivity = np.concatenate(cells).astype(np.int64)
        out += f"{key} {len(offsets)} {len(connectivity)}\nOFFSETS vtktypeint64\n".encode()
        out += offsets.astype(">i8").tobytes() + b"\n" if binary else " ".join(map(str, offsets)).encode() + b"\n"
        out += b"CONNECTIVITY vtktypeint64\n"
        out += (connectivity.astype(">i8").tobytes() + b"\n" if binary
                else " ".join(map(str, connectivity)).encode() + b"\n")
    else:
        flat = np.concatenate([[len(c)] + c for c in cells]).astype(np.int64)
        out += f"{key} {len(cells)} {len(flat)}\n".encode()
        out += flat.astype(">i4").tobytes() + b"\n" if binary else "\n".join(
            " ".join(map(str, [len(c)] + c)) for c in cells).encode() + b"\n"
    return out + b"POINT_DATA 3\n"


@pytest.mark.parametrize("binary", [False, True])
@pytest.mark.parametrize("new_layout", [False, True])
def test_legacy_polydata(tmp_path, binary, new_layout):
    path = tmp_path / "blob.vtk"
    path.write_bytes(legacy(binary, new_layout))
    result = p3d.props(path)
    assert result.facts.format == "vtk-polydata"
    assert_blob(result, "float32" if binary else "float64")


def test_triangle_strips_and_polygons(tmp_path):
    """A tetrahedron as one strip 0,2,1,3,0,2 (every second triangle reversed: a closed,
    outward solid) and the same tetrahedron's faces as a quad-free polygon list agree."""
    points = "0 0 0 3 0 0 0 2 0 0 0 5"
    strip = f"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n{points}\nTRIANGLE_STRIPS 1 7\n6 0 2 1 3 0 2\n"
    (tmp_path / "strip.vtk").write_text(strip)
    result = p3d.props(tmp_path / "strip.vtk")
    assert result.facts.closed and result.facts.faces == 4
    assert result.properties.volume == pytest.approx(5.0, rel=1e-15)   # 3 * 2 * 5 / 6
    # a square split as a fan: polygon 0 1 2 3 of a unit square, flat, area by the integrals' bounds
    square = "# vtk DataFile Version 3.0\nq\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 1 0 0 1 1 0 0 1 0\nPOLYGONS 1 5\n4 0 1 2 3\nLINES 1 3\n2 0 2\n"
    (tmp_path / "square.vtk").write_text(square)
    flat = p3d.props(tmp_path / "square.vtk")
    assert flat.facts.faces == 2 and any("left out" in w for w in flat.warnings)


@pytest.mark.parametrize("text, match", [
    (b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0\n", "numbers"),
    (b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\nPOLYGONS 1 4\n3 0 1 9\n",
     "outside"),
    (b'<VTKFile type="PolyData" compressor="vtkLZ4DataCompressor"><PolyData/></VTKFile>', "LZ4"),
    (b'<VTKFile type="PolyData"><PolyData><Piece>', "valid VTK XML"),
    (b'<VTKFile type="PolyData" header_type="UInt16"><PolyData/></VTKFile>', "not UInt32 or UInt64"),
    (b'<VTKFile type="PolyData" header_type="x"><PolyData/></VTKFile>', "header_type 'x' is not"),
    (b"# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 1 quad\n0 0 0\n", "POINTS section"),
])
def test_corrupt_polydata_is_one_error(tmp_path, text, match):
    path = tmp_path / ("bad.vtk" if text.startswith(b"#") else "bad.vtp")
    path.write_bytes(text)
    with pytest.raises(FormatError, match=match):
        p3d.props(path)


def test_polygons_of_mixed_sizes_are_fans():
    """Cells of 3, 4, 5 and 2 vertices: fans from each first vertex, none from the 2-cell."""
    from p3d_cli.io.vtp import _cells

    triangles = _cells(np.arange(14), np.array([3, 7, 12, 14]), False, "x")
    assert triangles.tolist() == [[0, 1, 2], [3, 4, 5], [3, 5, 6], [7, 8, 9], [7, 9, 10], [7, 10, 11]]


METADATA = (b"METADATA\nINFORMATION 2\nNAME L2_NORM_RANGE LOCATION vtkDataArray\nDATA 2 0.2 1.4\n"
            b"NAME L2_NORM_FINITE_RANGE LOCATION vtkDataArray\nDATA 2 0.2 1.4\n\n")


@pytest.mark.parametrize("binary", [False, True])
def test_vtk9_metadata_blocks_are_read_past(tmp_path, binary):
    """VTK 9's legacy writer puts a METADATA block (array ranges, ended by a blank line) after
    the points and after each cell array; such files were refused as 'no faces'."""
    text = legacy(binary, new_layout=True)
    text = text.replace(b"POLYGONS", METADATA + b"POLYGONS", 1)
    text = text.replace(b"CONNECTIVITY", METADATA.replace(b"L2_NORM", b"COMPONENT") + b"CONNECTIVITY", 1)
    text = text.replace(b"POINT_DATA", METADATA + b"POINT_DATA", 1)
    path = tmp_path / "vtk9.vtk"
    path.write_bytes(text)
    assert_blob(p3d.props(path), "float32" if binary else "float64")


CELLS = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\nPOINTS 4 float\n0 0 0 3 0 0 0 2 0 0 0 5\n"


@pytest.mark.parametrize("cells, match", [
    ("POLYGONS 4 16\n-1 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "-1, which is no index"),
    ("POLYGONS 400000000 16\n-1 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "larger than the file could hold"),
    ("POLYGONS 4 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n7 1 2 3\n", "add up to 20 values"),
    ("POLYGONS 2 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "add up to 8 values"),
    ("POLYGONS 4 16\n3 0 2 1e20\n3 0 1 3\n3 0 3 2\n3 1 2 3\n", "cannot be read"),
    ("POLYGONS -4 16\n3 0 2 1\n", "negative"),
    ("POINTS 1e20 float\n", "not an integer"),
])
def test_legacy_cell_counts_are_checked_before_use(tmp_path, cells, match):
    """A cell size of -1 made the classic-layout walk stand still: a hang (and in a --jobs batch
    every later result waited for it)."""
    path = tmp_path / "bad.vtk"
    path.write_text(CELLS + cells)
    with pytest.raises(FormatError, match=match):
        p3d.props(path)


def test_a_hostile_vtk_in_a_batch_loses_no_result(tmp_path):
    from click.testing import CliRunner

    from p3d_cli.cli.main import cli

    (tmp_path / "a.vtk").write_text(CELLS + "POLYGONS 4 16\n-1 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    (tmp_path / "b.vtk").write_text(CELLS + "POLYGONS 4 16\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n")
    run = CliRunner().invoke(cli, ["props", str(tmp_path / "a.vtk"), str(tmp_path / "b.vtk"), "--json",
                                   "--jobs", "2"])
    assert run.exit_code == 2
    records = [json.loads(line) for line in run.output.splitlines() if line.startswith("{")]
    assert [r.get("volume") for r in records if "error" not in r] == [pytest.approx(5.0)]


def vtp_of(connectivity: np.ndarray, offsets: np.ndarray, kind: str = "Float64") -> bytes:
    points = " ".join(map(str, [0, 0, 0, 3, 0, 0, 0, 2, 0, 0, 0, 5]))
    return (f'<VTKFile type="PolyData"><PolyData><Piece NumberOfPoints="4" NumberOfPolys="{len(offsets)}">'
            f'<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">{points}</DataArray></Points>'
            f'<Polys><DataArray type="{kind}" Name="connectivity" format="ascii">'
            f'{" ".join(map(repr, connectivity.tolist()))}</DataArray>'
            f'<DataArray type="{kind}" Name="offsets" format="ascii">{" ".join(map(repr, offsets.tolist()))}'
            "</DataArray></Polys></Piece></PolyData></VTKFile>").encode()


@pytest.mark.parametrize("bad", [1e20, float("nan"), -1.0, 2.5])
@pytest.mark.parametrize("where", ["connectivity", "offsets"])
def test_vtp_indices_that_are_no_index(tmp_path, bad, where):
    connectivity = np.array([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3], dtype=float)
    offsets = np.array([3, 6, 9, 12], dtype=float)
    (connectivity if where == "connectivity" else offsets)[1] = bad
    path = tmp_path / "bad.vtp"
    path.write_bytes(vtp_of(connectivity, offsets))
    with pytest.raises(FormatError, match="which is no index"):
        p3d.props(path)
    good = tmp_path / "good.vtp"
    good.write_bytes(vtp_of(np.array([0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3.0]), np.array([3, 6, 9, 12.0])))
    assert p3d.props(good).properties.volume == pytest.approx(5.0)


def zlib_bomb(inflated: int, declared: int | None = None) -> bytes:
    """A VTP whose points array is one zlib block of ``inflated`` zero bytes, declared as
    ``declared`` (default: the truth)."""
    block = zlib.compress(b"\0" * inflated, 9)
    head = struct.pack("<4I", 1, declared or inflated, declared or inflated, len(block))
    text = base64.b64encode(head) + base64.b64encode(block)
    return (b'<VTKFile type="PolyData" header_type="UInt32" compressor="vtkZLibDataCompressor"><PolyData>'
            b'<Piece><Points><DataArray type="Float32" NumberOfComponents="3" format="binary">' + text
            + b"</DataArray></Points></Piece></PolyData></VTKFile>")


def test_zlib_bomb_is_refused_by_its_declared_size(tmp_path, monkeypatch):
    """The 2 MB -> 2.3 GB bomb, scaled down: with a limit of 1 MB, 4 MB of zeros are refused
    before anything is inflated."""
    from p3d_cli.io import limits

    monkeypatch.setattr(limits, "MAX_INFLATED", 1 << 20)
    path = tmp_path / "bomb.vtp"
    path.write_bytes(zlib_bomb(4 << 20))
    assert path.stat().st_size < 10_000
    with pytest.raises(FormatError, match="more than p3d inflates"):
        p3d.props(path)


def test_zlib_block_inflating_past_its_declared_size_stops_there(tmp_path):
    path = tmp_path / "liar.vtp"
    path.write_bytes(zlib_bomb(4 << 20, declared=48))
    with pytest.raises(FormatError, match="inflates to more than the 48 bytes"):
        p3d.props(path)
