"""One grammar per text format: the fast paths and the careful parsers accept the same inputs
and give the same triangles, and agree with a small reference reader written here from the
grammar (issue 17). Token streams are generated around each grammar: signs, exponents,
suffixes, missing and extra fields, CR line ends, continuation lines."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from p3d_cli.errors import FormatError, InputError
from p3d_cli.io import obj, off
from p3d_cli.io.ply import ascii as ply_ascii
from p3d_cli.io.ply.header import Element, Header, Property
from p3d_cli.io.stl import ascii as stl_ascii

SETTINGS = settings(max_examples=int(__import__("os").environ.get("P3D_GRAMMAR_EXAMPLES", "150")), deadline=None, suppress_health_check=[HealthCheck.too_slow])

# --- the reference grammar ---------------------------------------------------------------

#: A decimal number, written out character class by character class (not shared with the code).
DIGITS = "0123456789"


def ref_number(word: str) -> float | None:
    """The value of a decimal number word, or None (a small hand-written scanner)."""
    i, n = 0, len(word)
    if i < n and word[i] in "+-":
        i += 1
    start = i
    while i < n and word[i] in DIGITS:
        i += 1
    whole = i - start
    frac = 0
    if i < n and word[i] == ".":
        i += 1
        f0 = i
        while i < n and word[i] in DIGITS:
            i += 1
        frac = i - f0
    if whole + frac == 0:
        return None
    if i < n and word[i] in "eE":
        i += 1
        if i < n and word[i] in "+-":
            i += 1
        e0 = i
        while i < n and word[i] in DIGITS:
            i += 1
        if i == e0:
            return None
    if i != n:
        return None
    value = float(word)
    return value if math.isfinite(value) else None


def ref_int(word: str) -> int | None:
    body = word[1:] if word[:1] in "+-" else word
    return int(word) if body and all(c in DIGITS for c in body) else None


# --- token strategies --------------------------------------------------------------------

good_numbers = st.one_of(
    st.integers(-50, 50).map(str),
    st.floats(-1e6, 1e6, allow_nan=False).map(repr),
    st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: f"{x:e}"),
    st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: f"{x:+.3E}"),
    st.sampled_from(["1.", ".5", "-.5", "+2", "0", "-0", "1e5", "3E-2", "1e300"]),
)
bad_numbers = st.sampled_from(["1f", "1v", "1_0", "-", "+", "- 3", "+ 3", "nan", "inf", "-inf", "1e999", "1e",
                               ".", "--1", "+-1", "1.2.3", "0x10", "1,5", "e5", "1e5e", "NaN", "1-2"])


def rarely(draw, odds: int = 40) -> bool:
    """True about once in ``odds`` draws: most generated files must be valid for the paths'
    agreement on what they read to be tested, a few invalid for their agreement on refusing."""
    return draw(st.integers(0, odds - 1)) == 0


def number(draw) -> str:
    return draw(bad_numbers) if rarely(draw) else draw(good_numbers)


def count(draw, usual: int, others: list[int]) -> int:
    return draw(st.sampled_from(others)) if rarely(draw, 15) else usual
gaps = st.sampled_from(["  ", "\t", " \t"])
endings = st.sampled_from(["\n", "\n", "\n", "\r\n", "\r"])


def joined(draw, words):
    out = ""
    for i, word in enumerate(words):
        out += ((draw(gaps) if rarely(draw, 12) else " ") if i else "") + word
    return out


# --- OBJ ---------------------------------------------------------------------------------

@st.composite
def obj_texts(draw):
    n_vertices = draw(st.integers(3, 6))
    lines = []
    for _ in range(n_vertices):
        size = count(draw, 3, [2, 4, 5, 6])
        lines.append(joined(draw, ["v"] + [number(draw) for _ in range(size)]))
    form = draw(st.sampled_from(["{a}", "{a}/{b}", "{a}//{b}", "{a}/{b}/{b}", "{a}/{b}/", "{a}//", "{a}/"]))
    for _ in range(draw(st.integers(1, 4))):
        corners = []
        for _ in range(count(draw, draw(st.sampled_from([3, 3, 4, 5])), [2, 1])):
            a = draw(bad_numbers) if rarely(draw) else \
                str(draw(st.one_of(st.integers(1, n_vertices), st.integers(-n_vertices, -1))))
            corner_form = draw(st.sampled_from(["{a}", "{a}/{b}/{b}"])) if rarely(draw, 10) else form
            b = draw(st.sampled_from(["0", "x", "-1", ""])) if rarely(draw) else "1"
            corners.append(corner_form.format(a=a, b=b))
        lines.append(joined(draw, ["f"] + corners))
    extras = draw(st.lists(st.sampled_from(["vt 0 0", "vn 0 0 1", "g part", "# note", "", "usemtl a", "s 1"]),
                           max_size=3))
    for extra in extras:
        lines.insert(draw(st.integers(0, len(lines))), extra)
    if rarely(draw, 8) and len(lines) > 1:
        at = draw(st.integers(0, len(lines) - 2))
        lines[at] += " \\"          # a continuation line
    ending = draw(endings)
    return ending.join(lines) + ending


def ref_obj(text: str):
    """Reference OBJ reader: (vertices, triangles) or None for an error."""
    text = text.replace("\r\n", "\n").replace("\r", "\n")
    vertices, triangles, statements, garbled = [], [], [], 0
    pending = ""
    for line in text.split("\n"):
        line = line.split("#", 1)[0]
        if line.rstrip().endswith("\\"):
            pending += line.rstrip()[:-1] + " "
            continue
        statements.append((pending + line).split())
        pending = ""
    if pending.split():
        statements.append(pending.split())
    count = 0
    for words in statements:
        if not words:
            continue
        count += 1
        if words[0] == "v":
            values = [ref_number(w) for w in words[1:]]
            if len(values) not in (3, 4, 6) or None in values:
                return None
            vertices.append(values[:3])
        elif words[0] == "f":
            if len(words) < 4:
                return None
            polygon = []
            for corner in words[1:]:
                parts = corner.split("/")
                if len(parts) > 3 or (len(parts) == 2 and not parts[1]):
                    return None
                if any(p and (ref_int(p) is None or ref_int(p) == 0) for p in parts[1:]):
                    return None
                index = ref_int(parts[0])
                if index is None or index == 0:
                    return None
                index = len(vertices) + index if index < 0 else index - 1
                if index < 0:
                    return None
                polygon.append(index)
            triangles += [(polygon[0], polygon[i], polygon[i + 1]) for i in range(1, len(polygon) - 1)]
        elif not words[0][:1].isalpha():
            garbled += 1
    if garbled * 2 > count or any(i >= len(vertices) for t in triangles for i in t):
        return None
    return np.array(vertices, dtype=float).reshape(-1, 3), np.array(triangles, dtype=np.int64).reshape(-1, 3)


@SETTINGS
@given(obj_texts())
def test_obj_fast_careful_and_reference_agree(text):
    data = text.encode()
    reference = ref_obj(text)
    try:
        vertices, faces, _ = obj._parse_lines("t.obj", data)
        careful = (vertices, faces)
    except FormatError:
        careful = None
    fast = obj._parse_fast(data)
    assert (careful is None) == (reference is None), text
    if careful is not None:
        np.testing.assert_array_equal(careful[0], reference[0])
        np.testing.assert_array_equal(careful[1], reference[1])
    if fast is not None:
        assert careful is not None, f"the fast path accepted what the careful parser rejects: {text!r}"
        np.testing.assert_array_equal(fast[0], careful[0])
        np.testing.assert_array_equal(fast[1], careful[1])


def outcome(read):
    """``(vertices, faces, warnings)`` or the error line of a reading."""
    try:
        vertices, faces, warnings = read()
    except FormatError as exc:
        return str(exc)
    return vertices, np.asarray(faces, dtype=np.int64).reshape(-1, 3), warnings


@SETTINGS
@given(obj_texts(), st.lists(st.sampled_from(["cstype bspline", "deg 3", "1/617/894", "  ", "\t# c", "f"]),
                             max_size=3), st.integers(1, 40), st.randoms(use_true_random=False))
def test_obj_chunks_read_by_either_parser_agree_with_the_careful_parser(text, odd, size, random):
    """Cut into chunks of a few lines, each read by the fast path or, when it holds anything
    else, by the careful parser: the same vertices, faces, warnings (line numbers in the file)
    and errors as the careful parser reading the whole text."""
    lines = text.replace("\r\n", "\n").replace("\r", "\n").split("\n")
    for line in odd:
        lines.insert(random.randint(0, len(lines)), line)
    data = "\n".join(lines).encode()

    def mixed():
        read = obj.read_chunks("t.obj", obj.chunks_of(obj._Bytes(data), size))
        if read is None:   # continuation lines or an index out of range: the whole file, carefully
            return obj._parse_lines("t.obj", data)
        vertices, pieces, warnings, _ = read
        return vertices, (np.concatenate(pieces) if pieces else np.zeros((0, 3))), warnings

    expected, got = outcome(lambda: obj._parse_lines("t.obj", data)), outcome(mixed)
    if isinstance(expected, str) or isinstance(got, str):
        assert got == expected
    else:
        np.testing.assert_array_equal(got[0], expected[0])
        np.testing.assert_array_equal(got[1], expected[1])
        assert got[2] == expected[2]


@pytest.mark.parametrize("form", ["{a}", "{a}/1", "{a}//1", "{a}/1/1", "{a}/1/", "{a}/-1/-1"])
def test_obj_fast_path_is_taken_for_exporter_output(form):
    """Exporters write one corner form per file: each takes the fast path, with every size."""
    faces = [(1, 2, 3), (1, 3, 4, 2), (-4, -3, -1)]
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
    text += "".join("f " + " ".join(form.format(a=a) for a in face) + "\n" for face in faces)
    fast = obj._parse_fast(text.encode())
    assert fast is not None
    np.testing.assert_array_equal(fast[1], [[0, 1, 2], [0, 2, 3], [0, 3, 1], [0, 1, 3]])


# --- OFF ---------------------------------------------------------------------------------

@st.composite
def off_texts(draw):
    n_vertices = draw(st.integers(3, 5))
    n_faces = draw(st.integers(1, 3))
    lines = ["OFF", f"{n_vertices} {n_faces} 0"]
    for _ in range(n_vertices):
        size = count(draw, draw(st.sampled_from([3, 3, 6])), [2])
        lines.append(joined(draw, [number(draw) for _ in range(size)]))
    for _ in range(n_faces):
        size = draw(st.sampled_from([3, 3, 4]))
        words = [str(size)] + [number(draw) if rarely(draw) else str(draw(st.integers(0, n_vertices - 1)))
                               for _ in range(size)]
        words += draw(st.sampled_from([[], [], ["255", "0", "0"], ["0.5", "0.5", "0.5", "1"]]))
        if rarely(draw, 15):
            words.insert(draw(st.integers(1, len(words))), draw(bad_numbers))
        lines.append(joined(draw, words))
    ending = draw(endings)
    return ending.join(lines) + ending


def ref_off(text: str):
    rows = [line.split("#", 1)[0].split() for line in text.replace("\r\n", "\n").replace("\r", "\n").split("\n")]
    rows = [r for r in rows if r]
    nv, nf = int(rows[1][0]), int(rows[1][1])
    vertices, triangles = [], []
    for row in rows[2:2 + nv]:
        values = [ref_number(w) for w in row]
        if len(values) < 3 or None in values:
            return None
        vertices.append(values[:3])
    for row in rows[2 + nv:2 + nv + nf]:
        values = [ref_number(w) for w in row]
        if None in values or not values or values[0] != int(values[0]):
            return None
        k = int(values[0])
        if k < 3 or k > len(values) - 1:
            return None
        corners = values[1:1 + k]
        if any(c != int(c) or not 0 <= c < nv for c in corners):
            return None
        corners = [int(c) for c in corners]
        triangles += [(corners[0], corners[i], corners[i + 1]) for i in range(1, k - 1)]
    return np.array(vertices)[np.array(triangles)]


@SETTINGS
@given(text=off_texts())
def test_off_agrees_with_reference(text, tmp_path_factory):
    path = tmp_path_factory.mktemp("off") / "t.off"
    path.write_bytes(text.encode())
    reference = ref_off(text)
    from p3d_cli.io.raw import open_input
    try:
        mine = off.load(open_input(str(path))).triangles()
    except FormatError:
        mine = None
    assert (mine is None) == (reference is None), text
    if mine is not None:
        np.testing.assert_array_equal(mine, reference)


# --- ASCII PLY ---------------------------------------------------------------------------

PLY_HEADER = Header("ascii", (
    Element("vertex", 3, (Property("x", "f4"), Property("y", "f4"), Property("z", "f4"))),
    Element("face", 2, (Property("vertex_indices", "i4", "u1"),))), 0)


@st.composite
def ply_bodies(draw):
    lines = []
    for _ in range(3):
        lines.append(joined(draw, [number(draw) for _ in range(count(draw, 3, [2, 4]))]))
    for _ in range(2):
        size = draw(st.sampled_from([3, 3, 4]))
        words = [str(size)] + [number(draw) if rarely(draw) else str(draw(st.integers(0, 2)))
                               for _ in range(size)]
        lines.append(joined(draw, words))
    if rarely(draw, 6):   # a record split over two lines
        at = draw(st.integers(0, len(lines) - 1))
        lines[at] = lines[at].replace(" ", "\n", 1)
    return "\n".join(lines) + draw(st.sampled_from(["\n", "\r\n", ""]))


def ref_ply(body: str):
    values = [ref_number(w) for w in body.split()]
    if None in values:
        return None
    pos, vertices, faces = 0, [], []
    for _ in range(3):
        vertices.append(values[pos:pos + 3])
        pos += 3
        if pos > len(values):
            return None
    for _ in range(2):
        if pos >= len(values):
            return None
        k = values[pos]
        if k < 0 or k != int(k) or pos + 1 + int(k) > len(values):
            return None
        faces.append(values[pos + 1:pos + 1 + int(k)])
        if any(c != int(c) or abs(c) > 2 ** 53 for c in faces[-1]):
            return None     # an index must be whole (and is range-checked later; huge ones here)
        pos += 1 + int(k)
    if pos != len(values):
        return "extra"
    return vertices, faces


@SETTINGS
@given(ply_bodies())
def test_ascii_ply_line_and_stream_parses_agree_with_reference(body):
    data = body.encode()
    reference = ref_ply(body)
    try:
        stream = ply_ascii._read_stream("t.ply", PLY_HEADER, data)
    except FormatError:
        stream = None
    try:
        lines = ply_ascii._read_lines("t.ply", PLY_HEADER, data)
    except FormatError:
        lines = None
    if reference is None:
        assert stream is None and lines is None, body
        return
    if reference == "extra":
        assert stream is not None and stream[1], body   # read, with a warning about the rest
        return
    assert stream is not None, body
    vertices, faces = reference
    for got in [stream] + ([lines] if lines is not None else []):
        tables = got[0]
        np.testing.assert_array_equal(np.stack(tables["vertex"], axis=1), np.array(vertices))
        corners, sizes = tables["face"]
        assert sizes.tolist() == [len(f) for f in faces]
        assert corners.tolist() == [c for f in faces for c in f]


# --- ASCII STL ---------------------------------------------------------------------------

@st.composite
def stl_texts(draw):
    indent = draw(st.sampled_from(["", " ", "  ", "\t"]))
    facets = []
    for _ in range(draw(st.integers(1, 4))):
        normal = [number(draw) for _ in range(count(draw, 3, [2, 4]))]
        corners = [[number(draw) for _ in range(count(draw, 3, [2, 4]))]
                   for _ in range(count(draw, 3, [4, 5, 2]))]
        lines = [joined(draw, ["facet", "normal"] + normal), indent + "outer loop"]
        lines += [indent * 2 + joined(draw, ["vertex"] + c) for c in corners]
        lines += [indent + "endloop", "endfacet"]
        if rarely(draw, 25):
            del lines[draw(st.integers(0, len(lines) - 1))]
        if rarely(draw, 25):
            at = draw(st.integers(0, len(lines) - 2))
            lines[at], lines[at + 1] = lines[at + 1], lines[at]
        if rarely(draw, 25):
            at = draw(st.integers(0, len(lines) - 1))
            lines[at] = lines[at].upper() if draw(st.booleans()) else lines[at] + " " + number(draw)
        facets.append("\n".join(lines))
    ending = draw(st.sampled_from(["\n", "\n", "\r\n"]))
    return ("solid x\n" + "\n".join(facets) + "\nendsolid x\n").replace("\n", ending)


def ref_stl(text: str):
    triangles, state, loop = [], "out", []
    for line in text.replace("\r", "").split("\n"):
        words = line.lower().split()
        if not words:
            continue
        key = words[0]
        if key in ("solid", "endsolid") and state == "out":
            continue
        if key == "facet" and state == "out":      # the normal is not used: not read
            state = "facet"
        elif words[:2] == ["outer", "loop"] and state == "facet":
            state, loop = "loop", []
        elif key == "vertex" and state == "loop" and len(words) == 4 and None not in [ref_number(w) for w in words[1:]]:
            loop.append([float(w) for w in words[1:]])
        elif key == "endloop" and state == "loop" and len(loop) >= 3:
            state = "endloop"
        elif key == "endfacet" and state == "endloop":
            triangles += [[loop[0], loop[i], loop[i + 1]] for i in range(1, len(loop) - 1)]
            state = "out"
        else:
            return None
    return np.array(triangles) if state == "out" and triangles else None


@SETTINGS
@given(stl_texts())
def test_ascii_stl_fast_careful_and_reference_agree(text):
    import io
    data = text.encode()
    reference = ref_stl(text)
    try:
        careful = stl_ascii.parse_lines("t.stl", io.BytesIO(data))
    except (FormatError, InputError):
        careful = None
    assert (careful is None) == (reference is None), text
    if careful is not None:
        np.testing.assert_array_equal(careful, reference)
    fast = stl_ascii.chunk_triangles(data)
    if fast is not None and len(fast):
        assert careful is not None, f"the fast path accepted what the careful parser rejects: {text!r}"
        np.testing.assert_array_equal(fast, careful)


def test_ascii_stl_fast_path_is_taken_for_exporter_output():
    facet = "facet normal 0 0 1\n  outer loop\n    vertex 0 0 0\n    vertex 1 0 0\n    vertex 0 1 0\n  endloop\nendfacet\n"
    assert stl_ascii.chunk_triangles(("solid x\n" + facet * 3 + "endsolid x\n").encode()).shape == (3, 3, 3)
    assert stl_ascii.chunk_triangles(("solid x\n" + facet.upper() * 3 + "endsolid x\n").encode()) is not None


@pytest.mark.parametrize("word, value", [("1.", 1.0), (".5", 0.5), ("-0", -0.0), ("+2e3", 2000.0)])
def test_reference_numbers(word, value):
    assert ref_number(word) == value
    assert all(ref_number(w) is None for w in ["1_0", "nan", "1e", "-", "1e999", "0x1"])
