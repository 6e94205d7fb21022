"""The PLY reader: ASCII and both binary byte orders, every type, extra elements and
properties, polygons, strict errors (a lying header must fail fast and allocate nothing)."""

from __future__ import annotations

import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from helpers.real_meshes import check_reference
from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import load_mesh, ply
import p3d_cli as p3d

CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_QUADS = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
CODES = dict(ply.TYPES)


def ply_bytes(fmt: str, elements, header_counts=None, comment=True) -> bytes:
    """A PLY file. ``elements``: (name, properties, records); a property is (type, name) or
    ("list", count_type, item_type, name); a record is a tuple with a sequence for each list."""
    lines = ["ply", f"format {fmt} 1.0"]
    if comment:
        lines.append("comment made by p3d tests")
    for i, (name, props, records) in enumerate(elements):
        count = len(records) if header_counts is None else header_counts[i]
        lines.append(f"element {name} {count}")
        for p in props:
            lines.append("property " + " ".join(p))
    lines.append("end_header")
    out = ("\n".join(lines) + "\n").encode()
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}.get(fmt)
    for _name, props, records in elements:
        for record in records:
            if order is None:
                words = []
                for p, value in zip(props, record):
                    words += [str(len(value))] + [repr(v) for v in value] if p[0] == "list" else [repr(value)]
                out += (" ".join(words) + "\n").encode()
                continue
            for p, value in zip(props, record):
                if p[0] == "list":
                    out += np.array(len(value), order + CODES[p[1]]).tobytes()
                    out += np.array(value, order + CODES[p[2]]).tobytes()
                else:
                    out += np.array(value, order + CODES[p[0]]).tobytes()
    return out


def cube_elements(vtype="float", face_list=("list", "uchar", "int", "vertex_indices"), quads=CUBE_QUADS):
    vertex = ("vertex", [(vtype, "x"), (vtype, "y"), (vtype, "z")], [tuple(map(float, v)) for v in CUBE_V])
    face = ("face", [face_list], [(list(q),) for q in quads])
    return [vertex, face]


def write(tmp_path: Path, data: bytes, name="m.ply") -> str:
    path = tmp_path / name
    path.write_bytes(data)
    return str(path)


FORMATS = ["ascii", "binary_little_endian", "binary_big_endian"]


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("vtype", ["float", "double", "float32", "float64"])
def test_cube_every_format_and_float_type(tmp_path, fmt, vtype):
    path = write(tmp_path, ply_bytes(fmt, cube_elements(vtype)))
    mesh = load_mesh(path)
    assert mesh.format == "ply" and mesh.face_count == 12
    single = fmt != "ascii" and vtype in ("float", "float32")
    assert mesh.coordinate_dtype == ("float32" if single else "float64")
    tris = mesh.triangles()
    v = np.array(CUBE_V, dtype=float)
    expected = np.array([v[[q[0], q[i], q[i + 1]]] for q in CUBE_QUADS for i in (1, 2)])
    np.testing.assert_array_equal(tris, expected)
    props = p3d.props(path).properties
    assert props.volume == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(props.inertia, np.eye(3) / 6, rtol=0, atol=1e-15)


@pytest.mark.parametrize("fmt", FORMATS)
def test_extra_elements_properties_and_face_lists(tmp_path, fmt):
    # Like trimesh's fuze.ply: colours and normals on vertices, a texcoord list and colours
    # on faces, plus unrelated elements before and after, and z y x in odd order and types.
    vprops = [("uchar", "red"), ("double", "z"), ("float", "nx"), ("int16", "y"), ("double", "x"),
              ("list", "uint8", "float", "weights"), ("uchar", "alpha")]
    verts = [(7, float(z), 0.5, int(y), float(x), [0.25, 0.75], 255) for x, y, z in CUBE_V]
    fprops = [("list", "uchar", "uint32", "vertex_index"), ("list", "uchar", "float", "texcoord"),
              ("uchar", "red"), ("ushort", "flags")]
    faces = [(list(q), [0.0] * 8, 1, 2) for q in CUBE_QUADS]
    elements = [("material", [("float", "shine"), ("list", "int", "char", "name")], [(0.5, [65, 66])]),
                ("vertex", vprops, verts), ("face", fprops, faces),
                ("edge", [("int", "vertex1"), ("int", "vertex2")], [(0, 1), (1, 2)])]
    mesh = load_mesh(write(tmp_path, ply_bytes(fmt, elements)))
    assert mesh.face_count == 12
    assert mesh.coordinate_dtype == "float64"  # x and z are double, y is int16: no float32
    props = p3d.props(write(tmp_path, ply_bytes(fmt, elements), "b.ply")).properties
    assert props.volume == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(props.center_of_mass, [0.5] * 3, rtol=0, atol=1e-15)


def test_float32_when_any_axis_is_float(tmp_path):
    elements = cube_elements("double")
    elements[0] = ("vertex", [("double", "x"), ("float", "y"), ("double", "z")], elements[0][2])
    mesh = load_mesh(write(tmp_path, ply_bytes("binary_little_endian", elements)))
    assert mesh.coordinate_dtype == "float32"
    assert p3d.props(write(tmp_path, ply_bytes("binary_little_endian", elements), "b.ply")
                      ).properties.volume == pytest.approx(1.0, rel=1e-15)


@pytest.mark.parametrize("fmt", FORMATS)
def test_mixed_polygon_sizes_take_the_record_walk(tmp_path, fmt):
    # A cube whose top is a triangle pair and a pentagon-free mix: two triangles, five quads,
    # written with the triangles first so the first record's length (3) is not everyone's.
    quads = CUBE_QUADS[1:]
    bottom = [(0, 3, 2), (0, 2, 1)]
    elements = cube_elements(quads=bottom + quads)
    path = write(tmp_path, ply_bytes(fmt, elements))
    mesh = load_mesh(path)
    assert mesh.face_count == 2 + 2 * len(quads)
    tris = mesh.triangles()
    v = np.array(CUBE_V, dtype=float)
    expected = [v[list(t)] for t in bottom] + [v[[q[0], q[i], q[i + 1]]] for q in quads for i in (1, 2)]
    np.testing.assert_array_equal(tris, np.array(expected))
    assert p3d.props(path).properties.volume == pytest.approx(1.0, rel=1e-15)


def test_hexagon_fan_matches_trimesh(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    angles = np.linspace(0, 2 * np.pi, 6, endpoint=False)
    verts = [(float(np.cos(a)), float(np.sin(a)), 0.0) for a in angles] + [(0.0, 0.0, 1.0)]
    faces = [(list(range(5, -1, -1)),)] + [([i, (i + 1) % 6, 6],) for i in range(6)]
    elements = [("vertex", [("double", "x"), ("double", "y"), ("double", "z")], verts),
                ("face", [("list", "uchar", "int", "vertex_indices")], faces)]
    path = write(tmp_path, ply_bytes("ascii", elements))  # trimesh 5.2 cannot read mixed binary lists
    ours = load_mesh(path).triangles()
    binary = load_mesh(write(tmp_path, ply_bytes("binary_little_endian", elements), "b.ply")).triangles()
    np.testing.assert_array_equal(ours, binary)
    v = np.array(verts)
    hexagon = list(range(5, -1, -1))
    np.testing.assert_array_equal(ours[:4], np.array([v[[hexagon[0], hexagon[i], hexagon[i + 1]]]
                                                       for i in range(1, 5)]))
    theirs = trimesh.load(path, process=False, force="mesh")

    def canonical(tris):
        out = []
        for t in np.asarray(tris, dtype=float).tolist():
            c = [tuple(x) for x in t]
            i = c.index(min(c))
            out.append(tuple(c[i:] + c[:i]))
        return sorted(out)

    assert canonical(ours) == canonical(theirs.triangles)


def test_crlf_header_and_ascii(tmp_path):
    data = ply_bytes("ascii", cube_elements()).replace(b"\n", b"\r\n")
    mesh = load_mesh(write(tmp_path, data))
    assert mesh.face_count == 12
    assert p3d.props(write(tmp_path, data, "b.ply")).properties.volume == pytest.approx(1.0, rel=1e-15)


def test_ascii_records_split_over_lines_still_read(tmp_path):
    # The spec separates values by whitespace, not lines: the stream parse handles this layout.
    data = ply_bytes("ascii", cube_elements())
    head, body = data.split(b"end_header\n")
    body = body.replace(b" ", b"\n")
    mesh = load_mesh(write(tmp_path, head + b"end_header\n" + body))
    assert mesh.face_count == 12


# --- errors ------------------------------------------------------------------------------

def raises(tmp_path, data, kind=FormatError):
    with pytest.raises(kind) as info:
        load_mesh(write(tmp_path, data), format="ply")
    assert info.value.hint
    return info.value


@pytest.mark.parametrize("edit, words", [
    (lambda h: h.replace(b"format ascii 1.0", b"format utf8 1.0"), "unknown format"),
    (lambda h: h.replace(b"format ascii 1.0", b"format ascii 2.0"), "version"),
    (lambda h: h.replace(b"property float x", b"property float16 x"), "unknown property type 'float16'"),
    (lambda h: h.replace(b"property float x", b"property float"), "expected 'property"),
    (lambda h: h.replace(b"element vertex 8", b"element vertex eight"), "element NAME COUNT"),
    (lambda h: h.replace(b"property float x\n", b""), "no x property"),
    (lambda h: h.replace(b"vertex_indices", b"corners"), "no 'vertex_indices' list"),
    (lambda h: h.replace(b"list uchar int", b"list float int"), "list lengths must be integers"),
    (lambda h: h.replace(b"list uchar int", b"list uchar float"), "stored as floats"),
    (lambda h: h.replace(b"end_header", b"end_heading"), "end_header"),
    (lambda h: h.replace(b"comment made", b"bogus made"), "unexpected header line"),
    (lambda h: h.replace(b"format ascii 1.0\n", b""), "no 'format' line"),
])
def test_bad_headers(tmp_path, edit, words):
    err = raises(tmp_path, edit(ply_bytes("ascii", cube_elements())))
    assert words in err.what or words in err.hint


def test_not_ply(tmp_path):
    err = raises(tmp_path, b"plx\nformat ascii 1.0\nend_header\n")
    assert "'ply'" in err.what


def test_no_faces_is_input_error(tmp_path):
    elements = cube_elements()[:1]
    err = raises(tmp_path, ply_bytes("binary_little_endian", elements), InputError)
    assert "no faces" in err.what
    err = raises(tmp_path, ply_bytes("ascii", [elements[0], ("face", cube_elements()[1][1], [])]), InputError)
    assert "no faces" in err.what


@pytest.mark.parametrize("fmt", FORMATS)
@pytest.mark.parametrize("claimed", [[9, 6], [8, 7], [10 ** 12, 6], [8, 10 ** 12]])
def test_lying_header_counts_fail_fast_without_allocating(tmp_path, fmt, claimed):
    data = ply_bytes(fmt, cube_elements(), header_counts=claimed)
    tracemalloc.start()
    start = time.perf_counter()
    try:
        err = raises(tmp_path, data)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert time.perf_counter() - start < 2
    assert peak < 10_000_000
    if max(claimed) > 100:
        assert str(max(claimed)) in err.what  # the message names the lie
    # A count off by one shifts the next element; it must still fail, whatever it trips on.


@pytest.mark.parametrize("fmt", ["binary_little_endian", "binary_big_endian"])
@pytest.mark.parametrize("cut", [1, 5, 30])
def test_truncated_binary(tmp_path, fmt, cut):
    data = ply_bytes(fmt, cube_elements())
    err = raises(tmp_path, data[:-cut])
    assert "face" in err.what


def test_truncated_binary_with_varying_lists(tmp_path):
    data = ply_bytes("binary_little_endian", cube_elements(quads=[(0, 3, 2)] + CUBE_QUADS))
    err = raises(tmp_path, data[:-3])
    assert "ends inside the face records" in err.what


def test_truncated_ascii(tmp_path):
    data = ply_bytes("ascii", cube_elements())
    err = raises(tmp_path, data[:data.rfind(b"\n", 0, len(data) - 1)])
    assert "face" in err.what


@pytest.mark.parametrize("fmt", FORMATS)
def test_index_out_of_range(tmp_path, fmt):
    quads = list(CUBE_QUADS)
    quads[3] = (1, 2, 8, 5)
    err = raises(tmp_path, ply_bytes(fmt, cube_elements(quads=quads)))
    assert "face 3" in err.what and "vertex 8" in err.what and "8 vertices" in err.what


@pytest.mark.parametrize("fmt", FORMATS)
def test_triangle_index_out_of_range(tmp_path, fmt):
    """Triangles of a binary file come as (n, 3) rows of the file's records: the message still
    names the face and the index."""
    triangles = [(q[0], q[i], q[i + 1]) for q in CUBE_QUADS for i in (1, 2)]
    triangles[7] = (5, 9, 6)
    err = raises(tmp_path, ply_bytes(fmt, cube_elements(quads=triangles)))
    assert "face 7" in err.what and "vertex 9" in err.what and "8 vertices" in err.what


def test_binary_triangles_are_read_where_they_lie(tmp_path):
    """A little-endian file's triangle indices reach the kernels as a view of its records (a
    count byte and three int32 each), not a copy, with the values written."""
    triangles = [(q[0], q[i], q[i + 1]) for q in CUBE_QUADS for i in (1, 2)]
    source = load_mesh(write(tmp_path, ply_bytes("binary_little_endian", cube_elements(quads=triangles))))
    _, (faces,) = source.indexed_arrays()
    assert not faces.flags.owndata and faces.strides == (13, 4) and faces.dtype == np.int32
    assert faces.tolist() == [list(t) for t in triangles]
    assert p3d.props(source).volume == 1.0


def test_negative_index(tmp_path):
    quads = list(CUBE_QUADS)
    quads[0] = (0, -1, 2, 1)
    err = raises(tmp_path, ply_bytes("binary_big_endian", cube_elements(quads=quads)))
    assert "vertex -1" in err.what


def test_face_with_two_vertices(tmp_path):
    err = raises(tmp_path, ply_bytes("ascii", cube_elements(quads=CUBE_QUADS + [(0, 1)])))
    assert "face 6 has 2 vertices" in err.what


def test_ascii_garbage_names_the_line(tmp_path):
    data = ply_bytes("ascii", cube_elements()).replace(b"1.0 1.0 0.0", b"1.0 oops 0.0", 1)
    err = raises(tmp_path, data)
    assert "line" in err.where and "'oops'" in err.what


def test_ascii_fractional_index(tmp_path):
    data = ply_bytes("ascii", cube_elements()).replace(b"4 0 3 2 1", b"4 0 3 2.5 1")
    err = raises(tmp_path, data)
    assert "2.5" in err.what


def test_trailing_bytes_warn(tmp_path):
    mesh = load_mesh(write(tmp_path, ply_bytes("binary_little_endian", cube_elements()) + b"xyz"))
    assert any("3 trailing bytes" in w for w in mesh.warnings)


# --- real meshes -------------------------------------------------------------------------

@pytest.mark.parametrize("name, dtype", [("trimesh__fuze.ply", "float32"), ("common3d__horse.ply", "float32"),
                                         ("trimesh__bunny.ply", "float64")])
def test_real_ply_matches_reference(real_meshes, reference, name, dtype):
    path = str(real_meshes / name)
    mesh = load_mesh(path)
    assert mesh.format == "ply" and mesh.coordinate_dtype == dtype
    assert mesh.face_count == reference[name]["faces"]
    check_reference(p3d.props(path).properties, reference[name])


def test_header_words_in_comments_and_non_ascii_comments(tmp_path):
    data = ply_bytes("binary_little_endian", cube_elements())
    data = data.replace(b"comment made by p3d tests", "comment end_header here, by Jürgen".encode())
    mesh = load_mesh(write(tmp_path, data))
    assert mesh.face_count == 12
