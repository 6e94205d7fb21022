"""The OBJ reader: every statement form, fan order, relative indices, strict errors, real data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from helpers.real_meshes import check_reference

import p3d_cli as p3d
from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import load_mesh, obj
from p3d_cli.io.raw import open_input

# A unit cube [0, 1]^3 as six outward quads (1-based, as OBJ writes them).
CUBE_V = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
CUBE_QUADS = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (4, 1, 5, 8)]


def write(tmp_path: Path, text: str, name: str = "m.obj", newline: str = "\n") -> str:
    path = tmp_path / name
    path.write_bytes(text.replace("\n", newline).encode())
    return str(path)


def cube_text(face=lambda q: "f " + " ".join(map(str, q))) -> str:
    lines = ["# cube", "mtllib cube.mtl", "o cube"]
    lines += [f"v {x} {y} {z}" for x, y, z in CUBE_V]
    lines += ["g sides", "usemtl steel", "s off"]
    lines += [face(q) for q in CUBE_QUADS]
    return "\n".join(lines) + "\n"


def canonical(triangles: np.ndarray) -> list:
    """Triangles as sorted tuples of corner tuples, each rotated to start at its least corner
    (keeps the winding, forgets which corner is first and the order of triangles)."""
    out = []
    for tri in np.asarray(triangles, dtype=np.float64).tolist():
        corners = [tuple(c) for c in tri]
        i = corners.index(min(corners))
        out.append(tuple(corners[i:] + corners[:i]))
    return sorted(out)


def test_quads_split_as_fans_from_first_vertex(tmp_path):
    mesh = load_mesh(write(tmp_path, cube_text()))
    assert mesh.format == "obj" and mesh.coordinate_dtype == "float64"
    assert mesh.face_count == 12
    tris = mesh.triangles()
    v = np.array(CUBE_V, dtype=float)
    expected = []
    for q in CUBE_QUADS:
        a, b, c, d = (np.array(q) - 1).tolist()
        expected += [v[[a, b, c]], v[[a, c, d]]]
    np.testing.assert_array_equal(tris, np.array(expected))


def test_cube_volume_and_inertia_exact(tmp_path):
    props = p3d.props(write(tmp_path, cube_text())).properties
    assert props.volume == pytest.approx(1.0, rel=1e-15)
    np.testing.assert_allclose(props.center_of_mass, [0.5, 0.5, 0.5], rtol=0, atol=1e-15)
    np.testing.assert_allclose(props.inertia, np.eye(3) / 6, rtol=0, atol=1e-15)


@pytest.mark.parametrize("form", ["{i}", "{i}/{i}", "{i}//{i}", "{i}/{i}/{i}"])
def test_corner_forms_give_the_same_triangles(tmp_path, form):
    text = cube_text(lambda q: "f " + " ".join(form.format(i=i) for i in q))
    text = text.replace("g sides", "vt 0 0\nvt 1 0\nvn 0 0 1\ng sides")
    text += "".join(f"vt {i} 0\nvn 0 {i} 0\n" for i in range(10))  # enough for every index
    plain = load_mesh(write(tmp_path, cube_text(), "plain.obj")).triangles()
    np.testing.assert_array_equal(load_mesh(write(tmp_path, text)).triangles(), plain)
    assert obj._parse_fast(text.encode()) is not None  # the vectorised path handles every form


def test_mixed_corner_forms_and_sizes_use_careful_path_correctly(tmp_path):
    text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nf 1/1 2/2/2 3//3 4\nf 1 2 5\n"
    tris = load_mesh(write(tmp_path, text)).triangles()
    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
    np.testing.assert_array_equal(tris, v[[[0, 1, 2], [0, 2, 3], [0, 1, 4]]])


def test_ngon_fan_order_matches_trimesh(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    n = 22  # docs/method.md, "Formats in the wild": 22-sided faces occur
    angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
    ring = [f"v {float(np.cos(a))!r} {float(np.sin(a))!r} 0" for a in angles]
    text = "\n".join(ring + ["v 0 0 1", "f " + " ".join(str(i) for i in range(n, 0, -1))]
                     + [f"f {i + 1} {i % n + 2 if i + 1 < n else 1} {n + 1}" for i in range(n)]) + "\n"
    path = write(tmp_path, text)
    ours = load_mesh(path).triangles()
    assert len(ours) == (n - 2) + n
    # Ours is the fan (v0, vi, vi+1) in file order.
    polygon = [n - 1 - k for k in range(n)]
    v = np.array([[np.cos(a), np.sin(a), 0] for a in angles] + [[0, 0, 1]])
    fan = [v[[polygon[0], polygon[i], polygon[i + 1]]] for i in range(1, n - 1)]
    np.testing.assert_array_equal(ours[:n - 2], np.array(fan))
    theirs = trimesh.load(path, process=False, force="mesh")
    assert canonical(ours) == canonical(theirs.triangles)


def test_quads_match_trimesh_triangulation_on_real_spot(real_meshes, tmp_path):
    trimesh = pytest.importorskip("trimesh")
    path = str(real_meshes / "common3d__spot_quadrangulated.obj")
    # trimesh turns vt lines into a texture, which needs Pillow: give it the same polygons
    # without texture or normal references.
    import re

    text = re.sub(r"^v[tn] .*\n", "", open(path).read(), flags=re.M)
    plain = tmp_path / "spot_plain.obj"
    plain.write_text(re.sub(r"/\S*", "", text))
    theirs = trimesh.load(str(plain), process=False, force="mesh", maintain_order=True)
    assert len(theirs.triangles) == 5856
    assert canonical(load_mesh(path).triangles()) == canonical(theirs.triangles)


def test_negative_indices_are_relative_to_the_face_line(tmp_path):
    text = ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n"
            "v 5 5 5\nv 6 5 5\nv 5 6 5\nf -3 -2 -1\nf 1 -2 -1\n")
    tris = load_mesh(write(tmp_path, text)).triangles()
    fast = obj._parse_fast(text.encode())
    assert fast is not None  # interleaved runs of v and f lines stay on the vectorised path
    np.testing.assert_array_equal(fast[0][fast[1]], tris)
    np.testing.assert_array_equal(tris[0], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    np.testing.assert_array_equal(tris[1], [[5, 5, 5], [6, 5, 5], [5, 6, 5]])
    np.testing.assert_array_equal(tris[2], [[0, 0, 0], [6, 5, 5], [5, 6, 5]])


def test_negative_indices_with_slashes_match_positive(tmp_path):
    pos = cube_text(lambda q: "f " + " ".join(f"{i}/1/1" for i in q))
    neg = cube_text(lambda q: "f " + " ".join(f"{i - 9}/1/1" for i in q))  # 8 vertices before
    a = load_mesh(write(tmp_path, pos.replace("g sides", "vt 0 0\nvn 0 0 1\ng sides"), "p.obj")).triangles()
    b = load_mesh(write(tmp_path, neg.replace("g sides", "vt 0 0\nvn 0 0 1\ng sides"), "n.obj")).triangles()
    np.testing.assert_array_equal(a, b)


def test_crlf_comments_w_and_continuations(tmp_path):
    crlf = load_mesh(write(tmp_path, cube_text(), "crlf.obj", newline="\r\n")).triangles()
    plain = load_mesh(write(tmp_path, cube_text(), "plain.obj")).triangles()
    np.testing.assert_array_equal(crlf, plain)
    text = cube_text().replace("v 1 1 1", "v 1 1 1 1.0  # with w and a comment")
    text = text.replace("f 5 6 7 8", "f 5 6 \\\n 7 8")
    np.testing.assert_array_equal(load_mesh(write(tmp_path, text, "odd.obj")).triangles(), plain)


def test_decimal_text_parsed_as_float64(tmp_path):
    text = "v 0.1 0.2 0.3\nv 1e-3 2.5E+2 -0\nv 0.30000000000000004 1 1\nf 1 2 3\n"
    tris = load_mesh(write(tmp_path, text)).triangles()
    assert tris.dtype == np.float64
    assert tris[0, 0].tolist() == [0.1, 0.2, 0.3]
    assert tris[0, 2, 0] == 0.30000000000000004


def test_unknown_statement_is_ignored_with_a_warning(tmp_path):
    mesh = load_mesh(write(tmp_path, cube_text() + "cstype bspline\n"))
    assert mesh.face_count == 12
    assert any("cstype" in w for w in mesh.warnings)


def test_looks_like_obj():
    assert obj.looks_like_obj(b"# comment\n\nv 1 2 3\n")
    assert obj.looks_like_obj(b"mtllib a.mtl\no x\n")
    assert not obj.looks_like_obj(b"solid x\nfacet normal 0 0 0\n")
    assert not obj.looks_like_obj(b"v 1 2 3\0\0")


# --- errors ------------------------------------------------------------------------------

def raises(tmp_path, text, kind=FormatError):
    with pytest.raises(kind) as info:
        load_mesh(write(tmp_path, text))
    return info.value


def test_index_out_of_range_names_line_and_index(tmp_path):
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n# c\nf 1 2 3\nf 1 2 7\n")
    assert "line 6" in err.where and "7" in err.what and "3 vertices" in err.what and err.hint


def test_index_out_of_range_with_slashes(tmp_path):
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 9/1\n")
    assert "line 5" in err.where and "9" in err.what


def test_relative_index_before_first_vertex(tmp_path):
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n")
    assert "line 3" in err.where and "-3" in err.what


def test_index_zero(tmp_path):
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n")
    assert "line 4" in err.where and "0" in err.what


def test_no_faces_is_input_error(tmp_path):
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\n", InputError)
    assert not isinstance(err, FormatError)
    assert "no faces" in err.what and "3 vertices" in err.what


@pytest.mark.parametrize("text, line, word", [
    ("v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", 1, "v X Y Z"),
    ("v 0 0 0\nv 1 0 x\nv 0 1 0\nf 1 2 3\n", 2, "v X Y Z"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", 4, "at least 3"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3a\n", 4, "3a"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/ 2/3 3\n", 4, None),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n12 13 14\n7 8 9\n1 2 3\n4 5 6\n0 0 0\nf 1 2 3\n", 4, "unexpected"),  # mostly no OBJ
])
def test_malformed_lines_name_the_line(tmp_path, text, line, word):
    err = raises(tmp_path, text)
    assert f"line {line}" in err.where
    if word:
        assert word in err.what


def test_malformed_corner_after_slash(tmp_path):
    # 'f 1/ 2/3 3' is not a valid corner list; it must not be read as two corners.
    err = raises(tmp_path, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/0 2/1 3/1\n")
    assert "line 5" in err.where


def test_binary_garbage(tmp_path):
    path = tmp_path / "g.obj"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(FormatError) as info:
        load_mesh(str(path))
    assert "line 1" in info.value.where


def test_fast_and_careful_paths_agree(tmp_path):
    rng = np.random.default_rng(7)
    v = rng.normal(size=(50, 3))
    sizes = rng.integers(3, 7, size=40)
    faces = [rng.choice(50, size=k, replace=False) + 1 for k in sizes]
    text = "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in v.tolist())
    text += "".join("f " + " ".join(f"{i}/{i}/{i}" for i in f) + "\n" for f in faces)
    raw = open_input(write(tmp_path, text))
    data = raw.read_all()
    fast = obj._parse_fast(data)
    assert fast is not None
    careful = obj._parse_lines(raw.where, data)
    np.testing.assert_array_equal(fast[0], careful[0])
    np.testing.assert_array_equal(fast[1], careful[1])
    assert len(fast[1]) == int((sizes - 2).sum())


# --- real meshes -------------------------------------------------------------------------

def test_real_obj_matches_reference(real_meshes, reference):
    name = "common3d__spot_quadrangulated.obj"
    path = str(real_meshes / name)
    mesh = load_mesh(path)
    assert mesh.format == "obj" and mesh.face_count == reference[name]["faces"]
    check_reference(p3d.props(path).properties, reference[name])


def many_chunk_text(extra: dict[int, str] | None = None) -> str:
    """More than two obj_fast.CHUNKs of text: 30,000 vertices, then 40,000 faces (triangles,
    quads, relative indices); ``extra`` inserts lines before the given line indices."""
    rng = np.random.default_rng(11)
    v = rng.normal(size=(30_000, 3))
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    for k in range(40_000):
        corners = rng.choice(30_000, size=3 + (k % 7 == 0), replace=False) + 1
        lines.append("f " + " ".join(str(c - 30_001) if k % 5 == 0 else str(c) for c in corners))
    for at, line in sorted((extra or {}).items(), reverse=True):
        lines.insert(at, line)
    return "\n".join(lines) + "\n"


def careful_reading(path: str):
    raw = open_input(path)
    return obj.parse_lines(raw.where, [raw.read_all()])


def test_a_file_of_many_chunks_reads_as_the_careful_parser_reads_it(tmp_path):
    # Faces in many chunks, kept as per-chunk int32 pieces, give the careful parser's
    # triangles, in order, and the mesh source reads the pieces as one.
    from p3d_cli.io.obj.fast import CHUNK, chunks_of

    text = many_chunk_text()
    assert len(text) > 2 * CHUNK
    path = write(tmp_path, text)
    with open(path, "rb") as stream:
        vertices, pieces, warnings, careful = obj.read_chunks(path, chunks_of(stream))
    assert careful == 0 and warnings == ()
    assert len(pieces) > 1 and all(piece.dtype == np.int32 for piece in pieces)
    careful_vertices, careful_faces, _ = careful_reading(path)
    np.testing.assert_array_equal(vertices, careful_vertices)
    np.testing.assert_array_equal(np.concatenate(pieces), careful_faces)
    mesh = load_mesh(path)
    assert mesh.face_count == len(careful_faces)
    np.testing.assert_array_equal(mesh.triangles(), careful_vertices[careful_faces])


def test_odd_lines_send_only_their_chunks_to_the_careful_parser(tmp_path):
    # An unknown statement among the vertices and a stray corner line among the faces: two
    # chunks read carefully, the rest fast; the same triangles and the same warnings (with the
    # file's line numbers) as the careful parser reading the whole file.
    from p3d_cli.io.obj.fast import chunks_of

    text = many_chunk_text({20_000: "cstype bspline", 50_000: "1/617/894", 50_001: "deg 3"})
    path = write(tmp_path, text)
    with open(path, "rb") as stream:
        vertices, pieces, warnings, careful = obj.read_chunks(path, chunks_of(stream))
    assert careful == 2
    careful_vertices, careful_faces, careful_warnings = careful_reading(path)
    assert warnings == careful_warnings
    assert "line 20001" in warnings[0] and "cstype, deg" in warnings[0]
    assert "line 50002: '1/617/894'" in warnings[1]
    np.testing.assert_array_equal(vertices, careful_vertices)
    np.testing.assert_array_equal(np.concatenate(pieces), careful_faces)


@pytest.mark.parametrize("bad, message", [("v 1 2 x", "line 45001: expected 'v X Y Z"),
                                          ("f 1 2", "line 45001: a face needs at least 3 vertices")])
def test_an_error_in_a_later_chunk_names_its_line_in_the_file(tmp_path, bad, message):
    path = write(tmp_path, many_chunk_text({45_000: bad}))
    with pytest.raises(FormatError) as info:
        load_mesh(path)
    assert message in str(info.value)


def test_an_index_out_of_range_in_a_later_chunk_names_its_line(tmp_path):
    path = write(tmp_path, many_chunk_text({60_000: "f 1 2 30001"}))
    with pytest.raises(FormatError) as info:
        load_mesh(path)
    assert "line 60001" in info.value.where and "30001 is out of range" in str(info.value)


@pytest.mark.parametrize("cuts", [[], [5], [1, 2, 3], [16383, 16384, 16385], [40000], [0, 0, 7, 50000]])
def test_pieces_of_a_face_list_give_the_blocks_of_the_whole(cuts):
    from p3d_cli.io.source import BLOCK, _blocks_of

    whole = np.arange(3 * 60_000).reshape(-1, 3)
    bounds = [0, *sorted(cuts), len(whole)]
    pieces = [whole[a:b] for a, b in zip(bounds, bounds[1:])]
    got = list(_blocks_of(pieces, BLOCK))
    expected = [whole[i:i + BLOCK] for i in range(0, len(whole), BLOCK)]
    assert len(got) == len(expected)
    for a, b in zip(got, expected):
        np.testing.assert_array_equal(a, b)
