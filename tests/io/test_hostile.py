"""Hostile and odd inputs (issue 17): each ends in a right result or one p3d error naming where
and what; never a crash, a signal, status 3, a hang or a numpy warning."""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import load_mesh
from p3d_cli.io.raw import open_input

TRI_V = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"


def write(tmp_path: Path, data: bytes | str, name: str) -> str:
    path = tmp_path / name
    path.write_bytes(data.encode() if isinstance(data, str) else data)
    return str(path)


def error(path: str, kind=FormatError, fmt=None) -> FormatError:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a numpy RuntimeWarning is a failure too
        with pytest.raises(kind) as info:
            load_mesh(path, fmt)
    assert info.value.hint
    return info.value


def read(path: str, fmt=None):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mesh = load_mesh(path, fmt)
        return mesh, mesh.triangles()


# --- binary PLY: lengths and offsets -----------------------------------------------------

def binary_ply(count_type: str, item_type: str, first_length: int, faces: int = 1) -> bytes:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {faces}\nproperty list {count_type} {item_type} vertex_indices\n"
              "end_header\n").encode()
    codes = {"uchar": "<B", "ushort": "<H", "uint": "<I", "int": "<i"}
    body = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes()
    body += struct.pack(codes[count_type], first_length) + np.array([0, 1, 2], "<u2").tobytes()
    return header + body


@pytest.mark.parametrize("count_type, length", [("uint", 1073741823), ("uint", 4_000_000_000),
                                                ("int", 2_000_000_000), ("uint", 2 ** 31)])
def test_huge_binary_list_length_is_a_format_error_not_a_crash(tmp_path, count_type, length):
    data = binary_ply(count_type, "ushort", length)
    path = write(tmp_path, data, "huge.ply")
    # In a child process: a segmentation fault must show as a signal, not kill the test run.
    code = ("import sys\nfrom p3d_cli.io import load_mesh\nfrom p3d_cli.errors import FormatError\n"
            f"try:\n    load_mesh({path!r})\nexcept FormatError as e:\n    print(e.what)\n    sys.exit(2)\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "face" in done.stdout


def test_negative_signed_list_length(tmp_path):
    err = error(write(tmp_path, binary_ply("int", "ushort", -5), "neg.ply"))
    assert "negative list length -5" in err.what


# --- PLY: duplicate and empty elements ---------------------------------------------------

VERTEX = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
FACE = "element face 1\nproperty list uchar int vertex_indices\n"
STRIPS = "element tristrips 1\nproperty list int int vertex_indices\n"


@pytest.mark.parametrize("elements", [VERTEX + VERTEX + FACE, VERTEX + FACE + FACE, VERTEX + FACE + VERTEX,
                                      FACE + VERTEX + FACE, VERTEX + STRIPS + STRIPS])
def test_two_vertex_or_face_elements_are_refused(tmp_path, elements):
    data = f"ply\nformat ascii 1.0\n{elements}end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    err = error(write(tmp_path, data, "two.ply"))
    assert "a second" in err.what and "header line" in err.where


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian"])
def test_empty_list_element_is_read_past(tmp_path, fmt):
    head = (f"ply\nformat {fmt} 1.0\n{VERTEX}element edge 0\nproperty list uchar int vertex_indices\n"
            f"{FACE}end_header\n").encode()
    if fmt == "ascii":
        body = b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"
    else:
        body = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "<f4").tobytes() + b"\x03" + \
            np.array([0, 1, 2], "<i4").tobytes()
    mesh, tris = read(write(tmp_path, head + body, "edge.ply"))
    np.testing.assert_array_equal(tris, [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])


@pytest.mark.parametrize("fmt", ["ascii", "binary_little_endian", "binary_big_endian"])
def test_tristrips_are_read(tmp_path, fmt):
    """A square of two triangles as one strip 0 1 2 3: (0 1 2) and (2 1 3), both facing +z,
    plus a second strip after -1 that is degenerate at its join."""
    head = (f"ply\nformat {fmt} 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
            "element tristrips 1\nproperty list int int vertex_indices\nend_header\n").encode()
    points = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 2, 0]]
    strip = [0, 1, 2, 3, -1, 3, 1, 4, 4]
    if fmt == "ascii":
        body = "".join(f"{x} {y} {z}\n" for x, y, z in points) + f"{len(strip)} " + " ".join(map(str, strip)) + "\n"
        body = body.encode()
    else:
        order = "<" if fmt.endswith("little_endian") else ">"
        body = np.array(points, order + "f4").tobytes() + np.array([len(strip)] + strip, order + "i4").tobytes()
    mesh, tris = read(write(tmp_path, head + body, "strip.ply"))
    p = np.array(points, dtype=float)
    np.testing.assert_array_equal(tris, p[[[0, 1, 2], [2, 1, 3], [3, 1, 4]]])
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert (normals[:2, 2] > 0).all()  # the alternating strip keeps one orientation


# --- text indices and numbers ------------------------------------------------------------

CUBE_OFF_V = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n"


@pytest.mark.parametrize("face, shown", [("3 0 1 inf", "inf"), ("3 0 1 1e29", "1e29"),
                                         ("3 0 1 99999999999999999999", "99999999999999999999"),
                                         ("3 0 1 -99999999999999999999", "-99999999999999999999")])
def test_off_huge_or_infinite_index(tmp_path, face, shown):
    err = error(write(tmp_path, f"OFF\n4 1 0\n{CUBE_OFF_V}{face}\n", "i.off"))
    assert "line 7" in err.where and shown in err.what


@pytest.mark.parametrize("corner", ["1e29", "99999999999999999999", "-99999999999999999999", "9223372036854775808"])
def test_obj_huge_index(tmp_path, corner):
    err = error(write(tmp_path, TRI_V + f"f 1 2 {corner}\n", "i.obj"))
    assert "line 5" in err.where and corner in err.what


def test_off_nan_vertex_names_the_line(tmp_path):
    err = error(write(tmp_path, "OFF\n4 1 0\n0 0 0\n1 nan 0\n0 1 0\n0 0 1\n3 0 1 2\n", "n.off"))
    assert "line 4" in err.where and "'nan'" in err.what


@pytest.mark.parametrize("text, line", [
    (TRI_V + "f 1f 3 2\n", 5), (TRI_V + "f 2 3 4 -\n", 5), ("v 1v 0 0\n" + TRI_V + "f 2 3 4\n", 1),
    (TRI_V + "f 1 + 3\n", 5), (TRI_V + "f 1 2 - 3\n", 5), ("v 1_0 0 0\n" + TRI_V + "f 2 3 4\n", 1),
    ("v inf 0 0\n" + TRI_V + "f 2 3 4\n", 1), ("v 1e999 0 0\n" + TRI_V + "f 2 3 4\n", 1),
    (TRI_V + "f 1/1/1/1 2/2/2 3/3/3\n", 5), (TRI_V + "vt 0 0\nf /1/1 2/1/1 3/1/1\n", 6),
])
def test_obj_one_grammar(tmp_path, text, line):
    err = error(write(tmp_path, text, "g.obj"))
    assert f"line {line}" in err.where


@pytest.mark.parametrize("face", ["3 1 2 + 3", "3 1 2 - 3", "3 1 2 3 -", "3 1_0 2 3"])
def test_off_and_ascii_ply_one_grammar(tmp_path, face):
    err = error(write(tmp_path, f"OFF\n4 1 0\n{CUBE_OFF_V}{face}\n", "g.off"))
    assert "line 7" in err.where
    ply = (f"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
           f"{FACE}end_header\n{CUBE_OFF_V}{face}\n")
    err = error(write(tmp_path, ply, "g.ply"))
    assert "line 14" in err.where


def test_ply_ascii_nan_and_overflow_are_not_numbers(tmp_path):
    for word in ("nan", "inf", "1e999"):
        ply = (f"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
               f"{FACE}end_header\n0 0 0\n1 {word} 0\n0 1 0\n3 0 1 2\n")
        err = error(write(tmp_path, ply, "n.ply"))
        assert "line 11" in err.where and repr(word) in err.what


# --- OBJ statements (issue 12) -----------------------------------------------------------

def big_obj(extra: str, at: int) -> str:
    lines = [f"v {i} {i * i % 7} {i % 3}" for i in range(300)]
    lines += [f"f {i + 1} {i + 2} {i + 3}" for i in range(0, 297)]
    lines.insert(at, extra)
    return "\n".join(lines) + "\n"


def test_bare_corner_line_is_skipped_with_one_warning(tmp_path):
    plain, tris = read(write(tmp_path, big_obj("", 400), "plain.obj"))
    mesh, odd = read(write(tmp_path, big_obj("1/617/894", 400), "odd.obj"))
    np.testing.assert_array_equal(odd, tris)
    assert len(mesh.warnings) == 1 and "line 401" in mesh.warnings[0] and "1/617/894" in mesh.warnings[0]
    assert "skipped 1 line" in mesh.warnings[0]


def test_many_stray_lines_are_skipped_and_counted_but_a_file_made_of_them_is_refused(tmp_path):
    from p3d_cli.errors import FormatError

    _, tris = read(write(tmp_path, big_obj("", 400), "plain.obj"))
    stray = "\n".join(["1/617/894"] * 60)          # 60 of 657 lines: a tenth of the file
    mesh, odd = read(write(tmp_path, big_obj(stray, 350), "stray.obj"))
    np.testing.assert_array_equal(odd, tris)
    assert len(mesh.warnings) == 1 and "skipped 60 lines" in mesh.warnings[0] and "line 351" in mesh.warnings[0]
    # More stray lines than statements: not an OBJ, refused at the first stray line.
    junk = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" + "1/2/3 4\n" * 5
    with pytest.raises(FormatError) as info:
        read(write(tmp_path, junk, "junk.obj"))
    assert "line 5" in info.value.where


def test_unknown_statements_counted_with_first_line(tmp_path):
    mesh, _ = read(write(tmp_path, big_obj("cstype bspline\ndeg 3", 310), "u.obj"))
    assert len(mesh.warnings) == 1
    assert "ignored 2 OBJ statements" in mesh.warnings[0] and "line 311" in mesh.warnings[0]


@pytest.mark.parametrize("corners", ["1/1/ 2/1/ 3/1/", "1// 2// 3//", "1//1 2/1/ 3//"])
def test_empty_trailing_corner_fields_are_valid(tmp_path, corners):
    mesh, tris = read(write(tmp_path, TRI_V + "vt 0 0\n" + f"f {corners}\n", "t.obj"))
    np.testing.assert_array_equal(tris, [[[0, 0, 0], [1, 0, 0], [0, 1, 0]]])


# --- STL ---------------------------------------------------------------------------------

FACET = "facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 0 1 0\n endloop\nendfacet\n"


@pytest.mark.parametrize("facet, line", [
    (FACET.replace("vertex 1 0 0", "vertex 1_0 0 0"), 4),
    (FACET.replace("normal 0 0 1", "normal 0 0").replace("vertex 0 0 0", "vertex 1 0 0 0"), 3),
    (FACET.replace("vertex 1 0 0", "vertex 1 - 0 0"), 4),
    (FACET.replace("vertex 1 0 0", "vertex 1 0 nan"), 4),
    (FACET.replace(" outer loop\n", ""), 2),
    (FACET.replace("endloop\n", "").replace("endfacet\n", "endfacet\n endloop\n"), 6),
])
def test_ascii_stl_one_grammar(tmp_path, facet, line):
    text = "solid x\n" + FACET * 3 + facet + FACET + "endsolid x\n"
    err = error(write(tmp_path, text, "g.stl"))
    assert f"line {line + 22}" in err.where


def test_ascii_stl_without_endsolid_warns(tmp_path):
    mesh, tris = read(write(tmp_path, "solid x\n" + FACET * 2, "open.stl"))
    assert len(tris) == 2 and any("endsolid" in w for w in mesh.warnings)
    mesh, _ = read(write(tmp_path, "solid x\n" + FACET * 2 + "endsolid x\n", "closed.stl"))
    assert not mesh.warnings


def test_binary_stl_with_large_coordinates_is_read(tmp_path):
    tri = np.array([[[0, 0, 0], [3e38, 0, 0], [0, 3e38, 0]], [[0, 0, 0], [0, 0, 3e38], [3e38, 0, 0]]], "<f4")
    record = np.zeros(2, dtype=[("n", "<f4", 3), ("c", "<f4", (3, 3)), ("a", "<u2")])
    record["c"] = tri
    path = write(tmp_path, b"\0" * 80 + struct.pack("<I", 2) + record.tobytes(), "big.stl")
    mesh, tris = read(path)
    np.testing.assert_array_equal(tris, tri)


# --- the path itself ---------------------------------------------------------------------

def test_fifo_without_writer_does_not_hang(tmp_path, monkeypatch):
    monkeypatch.setattr("p3d_cli.io.raw.FIFO_WAIT", 0.2)
    fifo = str(tmp_path / "pipe.stl")
    os.mkfifo(fifo)
    result = {}

    def target():
        try:
            open_input(fifo)
        except InputError as exc:
            result["error"] = exc

    thread = threading.Thread(target=target, daemon=True)
    thread.start()
    thread.join(60)
    assert not thread.is_alive(), "opening a FIFO with no writer blocked"
    assert "no data" in result["error"].what


def test_fifo_with_writer_is_read(tmp_path):
    fifo = str(tmp_path / "pipe.obj")
    os.mkfifo(fifo)
    text = (TRI_V + "f 1 2 3\n").encode()
    writer = subprocess.Popen([sys.executable, "-c", f"open({fifo!r}, 'wb').write({text!r})"])
    try:
        mesh = load_mesh(fifo)
        assert mesh.format == "obj" and mesh.face_count == 1
    finally:
        writer.wait(60)


@pytest.mark.parametrize("device", ["/dev/zero", "/dev/urandom", "/dev/null"])
def test_devices_are_refused(device):
    if not os.path.exists(device):
        pytest.skip(f"no {device}")
    with pytest.raises(InputError) as info:
        open_input(device)
    assert "device" in info.value.what


def test_symlink_loop_and_broken_link(tmp_path):
    a, b = tmp_path / "a.stl", tmp_path / "b.stl"
    os.symlink(b, a)
    os.symlink(a, b)
    with pytest.raises(InputError, match="loop of symbolic links"):
        open_input(str(a))
    broken = tmp_path / "c.stl"
    os.symlink(tmp_path / "missing.stl", broken)
    with pytest.raises(InputError, match="broken symbolic link"):
        open_input(str(broken))
    with pytest.raises(InputError, match="no such file"):
        open_input(str(tmp_path / "missing.stl"))


def test_fromstring_refuses_text_it_cannot_read_to_its_end_on_every_numpy():
    """Issue 24.3: numpy 1.24 (the declared minimum) only warns and returns the numbers before the
    bad word, where numpy 2 raises; the text readers' fast paths rely on the error."""
    import numpy as np
    import pytest as _pytest

    from p3d_cli.io.numbers import fromstring

    assert fromstring(b"1 2 3", np.float64).tolist() == [1.0, 2.0, 3.0]
    for text, dtype in ((b"1 2 x 4", np.float64), (b"1 2_0 3", np.int64), (b"1 2 3\n4 5 6 x", np.float64)):
        with _pytest.raises(ValueError):
            fromstring(text, dtype)
