"""The compiled kernels (``p3d_cli.mesh._kernels``) give the numpy code's results, bit for bit.

Each test runs the same input through the kernels and through the numpy code they replace
(``kernels.KERNELS`` set to None) and compares the bits. Skipped where the kernels are not
built (no compiler at install time: p3d then runs the numpy code, which is what the rest of the
suite tests), except under CI, whose install compiles them.
"""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from helpers.kernels import SAME_BITS, bits, needs_kernels, numpy_road
from helpers.real_meshes import REPO
from p3d_cli.io import load_mesh
from p3d_cli.io.source import array_source
from p3d_cli.mesh import kernels
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.closed import column_edge_keys
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.integrals import tetra_terms

KERNELS = kernels.KERNELS
pytestmark = needs_kernels

REAL = REPO.parent / "shared" / "real-meshes"
RECORD = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)), ("attr", "<u2")])


def test_built_under_ci():
    """CI installs with a compiler: the kernels must be there (else they are never tested)."""
    assert KERNELS is not None


def numpy_block(triangles: np.ndarray, origin: np.ndarray):
    """What ``MomentSums.add_columns`` and ``column_edge_keys`` make of one block."""
    cols = columns(triangles)
    keys = np.sort(column_edge_keys(cols))
    cols -= origin[None, :, None]
    terms, magnitude, weighted = tetra_terms(cols[0], cols[1], cols[2])
    return terms.sum(axis=1), float(magnitude.sum()), weighted, keys


def torus_mesh(u: int, v: int) -> tuple[np.ndarray, np.ndarray]:
    """The closed grid torus of ``2 u v`` faces (``test_paired.torus``), indexed."""
    from test_paired import torus

    triangles = torus(u, v).reshape(-1, 3)
    points, faces = np.unique(triangles, axis=0, return_inverse=True)
    return points, faces.reshape(-1, 3)


SIZES = [1, 2, 7, 8, 9, 16, 17, 127, 128, 129, 130, 255, 1000, 4097, 16383, 16384]


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("layout", ["float32", "float64", "stl-records"])
def test_block_sums_and_keys_are_numpys(n, layout):
    rng = np.random.default_rng(n)
    triangles = rng.normal(size=(n, 3, 3)) * 10.0 ** rng.integers(-3, 6) + rng.normal(size=3) * 50
    triangles[::5, 1] = triangles[::5, 0]               # sides whose ends coincide: no key
    triangles[::7] = np.round(triangles[::7])           # zeros, repeats, -0.0 after the shift
    triangles[::11, :, 2] = -0.0
    dtype = np.float64 if layout == "float64" else np.float32
    triangles = triangles.astype(dtype)
    if layout == "stl-records":                         # the file's strided 50-byte records
        records = np.zeros(n, RECORD)
        records["corners"] = triangles
        triangles = records["corners"]
    origin = rng.normal(size=3)
    if dtype == np.float32:
        origin = origin.astype(np.float32).astype(np.float64)
    totals, magnitude, weighted, keys = numpy_block(triangles, origin)
    got_keys = np.zeros(3 * n, np.uint64)
    _, finite, got, got_magnitude, got_weighted, written = KERNELS.block(triangles, *origin, got_keys, 0)
    assert finite
    if SAME_BITS:
        assert np.array_equal(bits(got), bits(totals))
        assert bits(got_magnitude) == bits(magnitude)
        assert np.array_equal(bits(got_weighted), bits(weighted))
    else:
        # Each sum's rounding is below n * eps times the sum of its terms' sizes: relative to
        # the sums themselves (the moments' sums have other units than the volume's magnitude).
        bound = 2 * n * np.finfo(np.float64).eps * magnitude
        np.testing.assert_allclose(got, totals, rtol=2 * n * np.finfo(np.float64).eps, atol=bound)
        np.testing.assert_allclose(got_magnitude, magnitude, rtol=2 * n * np.finfo(np.float64).eps)
        np.testing.assert_allclose(got_weighted, weighted, rtol=2 * n * np.finfo(np.float64).eps)
    got_keys = got_keys[:written]
    KERNELS.sort(got_keys)
    assert np.array_equal(got_keys, keys)


def test_bounds_and_nonfinite():
    triangles = np.arange(27, dtype=np.float32).reshape(3, 3, 3) - 13
    box, finite = KERNELS.bounds(triangles)
    flat = triangles.reshape(-1, 3).astype(np.float64)
    assert finite and box == tuple(flat.min(axis=0)) + tuple(flat.max(axis=0))
    for bad in (np.nan, np.inf, -np.inf):
        broken = triangles.copy()
        broken[1, 2, 0] = bad
        assert KERNELS.bounds(broken)[1] is False
        assert KERNELS.block(broken, 0.0, 0.0, 0.0, None, 0)[1] is False


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, 2**64 - 1), max_size=3000), st.integers(0, 63))
def test_sort_is_numpys(values, shift):
    # Narrow keys (shifted) and many equal ones take the radix sort's other branches.
    keys = np.array(values, dtype=np.uint64) >> np.uint64(shift)
    got = keys.copy()
    KERNELS.sort(got)
    assert np.array_equal(got, np.sort(keys))


@pytest.mark.parametrize("case", ["hashes", "pairs", "few values", "narrow", "zeros"])
def test_sort_large(case):
    rng = np.random.default_rng(1)
    n = 700_000                                          # past the in-cache size: the MSD split
    keys = {"hashes": lambda: rng.integers(0, 2**64 - 1, n, dtype=np.uint64, endpoint=True),
            "pairs": lambda: np.repeat(rng.integers(0, 2**63, n // 2, dtype=np.uint64) * np.uint64(2), 2)
            + np.tile(np.array([0, 1], np.uint64), n // 2),
            "few values": lambda: rng.integers(0, 5, n, dtype=np.uint64) << np.uint64(60),
            "narrow": lambda: rng.integers(0, 2**20, n, dtype=np.uint64),
            "zeros": lambda: np.zeros(n, np.uint64)}[case]()
    rng.shuffle(keys)
    got = keys.copy()
    KERNELS.sort(got)
    assert np.array_equal(got, np.sort(keys))


def test_buckets_sort_what_they_are_dealt():
    rng = np.random.default_rng(2)
    keys = rng.integers(0, 2**64 - 1, 300_000, dtype=np.uint64, endpoint=True)
    buckets = kernels.Buckets(keys.size)
    buckets.add(keys[:1000])                             # the numpy road's blocks
    triangles = rng.normal(size=(20_000, 3, 3))
    _, _, _, _, _, written = KERNELS.block(triangles, 0.0, 0.0, 0.0, buckets.keys, 0, buckets.fill, buckets.cap,
                                           buckets.shift)
    assert written == int(buckets.fill.sum()) - 1000
    expected = np.sort(np.concatenate([keys[:1000], column_edge_keys(columns(triangles))]))
    assert np.array_equal(buckets.sorted_keys(), expected)


def test_a_crowded_bucket_overflows_and_the_keys_are_made_again():
    """The same triangle 30,000 times: every key lands in a handful of buckets, which overflow;
    the analysis then makes the keys again in order and finds what the numpy code finds."""
    triangle = np.array([[0.5, 0.25, 1.0], [2.0, 0.5, 1.0], [1.0, 3.0, 1.5]], dtype=np.float32)
    source = array_source("stl-binary", np.repeat(triangle[None], 30_000, axis=0), "float32")
    compiled = analyze(source, "x")
    assert compiled.closed is False and compiled.bounding is False
    assert_same_analysis(source)


def attempt(source, options):
    try:
        return analyze(source, "x", **options)
    except Exception as exc:  # noqa: BLE001 - the same refusal is the same result
        return f"{type(exc).__name__}: {exc}"


def assert_same_analysis(source, **options):
    fast = attempt(source, options)
    slow = numpy_road(attempt, source, options)
    if isinstance(slow, str) or isinstance(fast, str):
        assert fast == slow
        return
    assert (fast.closed, fast.bounding, fast.boundary_edges, fast.face_count, fast.scale_exponent) == \
        (slow.closed, slow.bounding, slow.boundary_edges, slow.face_count, slow.scale_exponent)
    assert np.array_equal(bits(fast.bounds.min), bits(slow.bounds.min))
    assert np.array_equal(bits(fast.bounds.max), bits(slow.bounds.max))
    a, b = fast.moments, slow.moments
    if not SAME_BITS:
        # Before numpy 2.3: the two differ by no more than their stated bounds.
        for name in ("volume", "center", "central"):
            if getattr(b, name) is not None:
                bound = getattr(a.errors, name) + getattr(b.errors, name)
                assert np.all(np.abs(np.subtract(getattr(a, name), getattr(b, name))) <= bound), name
                np.testing.assert_allclose(getattr(a.errors, name), getattr(b.errors, name), rtol=1e-6)
        return
    assert bits(a.volume) == bits(b.volume)
    if b.center is not None:
        assert np.array_equal(bits(a.center), bits(b.center))
        assert np.array_equal(bits(a.central), bits(b.central))
    for name in ("volume", "center", "central"):
        assert np.array_equal(bits(getattr(a.errors, name)), bits(getattr(b.errors, name)))


def real_meshes():
    if not REAL.is_dir():
        return []
    return sorted(p for p in REAL.iterdir() if p.suffix.lower() in {".stl", ".ply", ".obj", ".off"})


@pytest.mark.parametrize("path", real_meshes() + sorted((REPO / "sample_meshes").glob("*.[so][tfb][lfj]")),
                         ids=lambda p: p.name)
def test_real_and_sample_meshes_analyse_alike(path):
    assert_same_analysis(load_mesh(str(path)))


def test_real_meshes_are_here_under_ci():
    if os.environ.get("CI") == "true":
        assert real_meshes(), f"{REAL} is missing"


@pytest.mark.parametrize("at", [(0.0, 0.0, 0.0), (1e8, -1e8, 3.0), (1e-70, 0.0, 0.0)])
@pytest.mark.parametrize("scale", [1.0, 1e-40, 1e40])
def test_tori_anywhere_analyse_alike(at, scale):
    """A closed torus and the same with a hole, far away, tiny and huge (the rescaled road)."""
    points, faces = torus_mesh(40, 24)
    points = points * scale + np.array(at)
    for chosen in (faces, faces[1:]):
        for dtype in (np.float64, np.float32):
            with np.errstate(over="ignore"):            # 1e40 in float32: infinities, refused alike
                triangles = points.astype(dtype)[chosen]
            source = array_source("stl-binary", triangles, np.dtype(dtype).name)
            assert_same_analysis(source)
            assert_same_analysis(source, rescale=True)
            assert_same_analysis(source, closed=False)


@pytest.mark.parametrize("signed_zeros", [False, True])
def test_blocks_with_a_zero_bound_analyse_alike(signed_zeros):
    """Blocks whose bounds touch 0 (of either sign) take their bounds from numpy's reductions
    and their sums and keys from the kernels: the numpy road's bits, zeros' signs included."""
    points, faces = torus_mesh(160, 60)                 # 19,200 faces: two blocks
    points = points - points.min(axis=0)                # every lower bound exactly 0
    if signed_zeros:
        points[points == 0.0] = -0.0                    # some -0.0 beside +0.0 in one block
        points[::3][points[::3] == -0.0] = 0.0
    for chosen in (faces, faces[1:]):
        for dtype in (np.float64, np.float32):
            source = array_source("stl-binary", points.astype(dtype)[chosen], np.dtype(dtype).name)
            assert_same_analysis(source)
            assert_same_analysis(source, closed=False)


def test_pure_numpy_switch(monkeypatch):
    monkeypatch.setenv("P3D_PURE_NUMPY", "1")
    assert kernels._load() is None
    monkeypatch.setenv("P3D_PURE_NUMPY", "0")
    assert kernels._load() is KERNELS


def test_json_output_alike(tmp_path):
    """The whole command: ``p3d props --json`` on a binary STL with the kernels and without."""
    import subprocess
    import sys

    records = np.zeros(5000, RECORD)
    rng = np.random.default_rng(3)
    records["corners"] = rng.normal(size=(5000, 3, 3)).astype(np.float32)
    path = tmp_path / "soup.stl"
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + np.uint32(5000).tobytes() + records.tobytes())
    outputs = []
    for pure in ("0", "1"):
        env = dict(os.environ, P3D_PURE_NUMPY=pure)
        done = subprocess.run([sys.executable, "-m", "p3d_cli", "props", str(path), "--json"], env=env,
                              capture_output=True, check=False)
        outputs.append((done.returncode, done.stdout))
    assert outputs[0] == outputs[1]
    assert json.loads(outputs[0][1])["closed"] is False


@pytest.mark.parametrize("degenerate", [False, True])
def test_side_keys_are_numpys(degenerate):
    from p3d_cli.mesh.closed import side_keys

    rng = np.random.default_rng(4)
    triangles = rng.normal(size=(3000, 3, 3))
    if degenerate:
        triangles[::3, 2] = triangles[::3, 0]
    cols = columns(triangles)
    keys, keep = side_keys(cols)
    want_keys, want_keep = numpy_road(side_keys, cols)
    assert np.array_equal(keys, want_keys)
    assert (keep is None) == (want_keep is None) == (not degenerate)
    if degenerate:
        assert np.array_equal(keep, want_keep)


@pytest.mark.parametrize("case", ["closed", "holes", "collisions", "soup", "none"])
def test_groups_are_numpys(case):
    """``unbalanced_groups`` and ``doubtful_edges`` from the one compiled scan."""
    from p3d_cli.mesh.boundary_sides import unbalanced_groups
    from p3d_cli.mesh.closed import doubtful_edges

    rng = np.random.default_rng(5)
    edges = rng.integers(0, 2**62, 50_000, dtype=np.uint64) * np.uint64(2)
    keys = np.concatenate([edges, edges + np.uint64(1)])        # every edge once each way
    if case == "holes":
        keys = keys[rng.random(keys.size) > 0.01]
    elif case == "collisions":                                   # balanced groups of four
        keys = np.concatenate([keys, keys[:100], keys[50_000:50_100]])
    elif case == "soup":
        keys = edges | rng.integers(0, 2, edges.size, dtype=np.uint64)
    elif case == "none":
        keys = keys[:0]
    keys = np.sort(keys)
    got, want = unbalanced_groups(keys), numpy_road(unbalanced_groups, keys)
    assert np.array_equal(got.ids, want.ids) and got.ids.dtype == want.ids.dtype
    assert (got.edges, got.sides, got.total) == (want.edges, want.sides, want.total)
    got, want = doubtful_edges(keys), numpy_road(doubtful_edges, keys)
    assert np.array_equal(got, want) and got.dtype == want.dtype
    if case == "collisions":
        assert got.size == 100


def torus_triangles(u: int, v: int) -> np.ndarray:
    points, faces = torus_mesh(u, v)
    return (points + [12.5, -7.25, 3]).astype(np.float32)[faces]


def assert_commands_alike(path) -> None:
    """``p3d check`` and ``p3d props`` (``--json``) give the same bytes, status and messages
    with the kernels and without, and no traceback."""
    if not SAME_BITS:
        pytest.skip("numpy before 2.3 sums in another order: the last bits differ (held to the bound above)")
    import subprocess
    import sys

    for command in ("check", "props"):
        outputs = []
        for pure in ("0", "1"):
            env = dict(os.environ, P3D_PURE_NUMPY=pure)
            done = subprocess.run([sys.executable, "-m", "p3d_cli", command, str(path), "--json"], env=env,
                                  capture_output=True, check=False)
            outputs.append((done.returncode, done.stdout, done.stderr))
        assert outputs[0] == outputs[1], command
        assert outputs[0][0] in (0, 1) and b"Traceback" not in outputs[0][2]


@pytest.mark.parametrize("case", ["closed", "holes", "flipped", "duplicate", "two shells", "degenerate"])
def test_commands_alike_on_large_meshes(tmp_path, case):
    """``p3d check`` and ``p3d props`` (``--json``) with the kernels and without, on meshes large
    enough for the bucketed keys (over 65,536 sides) and each kind of defect."""
    triangles = torus_triangles(160, 80)                             # 25,600 faces
    if case == "holes":
        triangles = triangles[np.arange(len(triangles)) % 100 != 0]
    elif case == "flipped":
        triangles[7] = triangles[7, ::-1]
    elif case == "duplicate":
        triangles = np.concatenate([triangles, triangles[:3]])
    elif case == "two shells":
        triangles = np.concatenate([triangles, triangles + np.float32(20)])
    elif case == "degenerate":
        triangles[11, 2] = triangles[11, 0]
    records = np.zeros(len(triangles), RECORD)
    records["corners"] = triangles
    path = tmp_path / f"{case}.stl"
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + np.uint32(len(records)).tobytes() + records.tobytes())
    assert_commands_alike(path)


@pytest.mark.parametrize("order", ["<", ">"])
def test_indexed_ply_alike(tmp_path, order):
    """A binary PLY of either byte order (the kernels read native arrays only: a big-endian
    file's are converted by the reader, or left to numpy) gives the same check and props."""
    points, faces = torus_mesh(160, 80)
    faces = faces[1:]                                                  # one hole
    name = "binary_little_endian" if order == "<" else "binary_big_endian"
    header = (f"ply\nformat {name} 1.0\nelement vertex {len(points)}\nproperty float x\nproperty float y\n"
              f"property float z\nelement face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    record = np.dtype([("n", "u1"), ("v", order + "i4", (3,))])
    rows = np.empty(len(faces), record)
    rows["n"], rows["v"] = 3, faces
    path = tmp_path / "torus.ply"
    with open(path, "wb") as f:
        f.write(header.encode() + points.astype(order + "f4").tobytes() + rows.tobytes())
    assert_commands_alike(path)


@pytest.mark.parametrize("scale", [(0.001, 0.001, 0.001), (-0.001, 0.001, 0.001)])
def test_placed_indexed_mesh_has_its_bounds(scale):
    """A placed OBJ (indexed: the kernels' own road) reports the placed bounds and moments of
    the same mesh as a binary STL (blocks of triangles): the placement's projection of every
    block must see the blocks, so the indexed road is not taken past it."""
    from p3d_cli import props
    from p3d_cli.geometry.placement import Placement

    placement = Placement(np.array(scale), np.eye(3), np.array([-0.005, 0.0, 0.02]))
    obj = props(str(REPO / "sample_meshes" / "bracket.obj"), placement)
    stl = props(str(REPO / "sample_meshes" / "bracket.stl"), placement)
    assert obj.facts.bounds is not None
    assert np.array_equal(obj.facts.bounds.min, stl.facts.bounds.min)
    assert np.array_equal(obj.facts.bounds.max, stl.facts.bounds.max)
    assert bits(obj.properties.center_of_mass).tolist() == bits(stl.properties.center_of_mass).tolist()



@pytest.mark.parametrize("kind", ["glb", "glb strided", "3mf"])
def test_unplaced_scene_object_is_indexed_and_alike(tmp_path, kind):
    """A scene file of one unplaced object (GLB, 3MF) is read as an indexed mesh, so the kernels
    read its vertices and faces as they are (a strided glTF accessor included): the same
    analysis, bit for bit, as its gathered blocks, and the same check and props with the
    kernels and without."""
    import dataclasses

    from helpers import threemf_writer
    from helpers.gltf_writer import Gltf

    points, faces = torus_mesh(160, 80)
    faces = faces[1:]                                                  # one hole
    if kind == "3mf":
        path = threemf_writer.package(tmp_path / "torus.3mf", threemf_writer.model(
            [threemf_writer.mesh_object(1, points, faces)], items=[(1, None, None)], unit="meter"))
    else:
        gltf = Gltf()
        if kind == "glb strided":                                      # x y z and a pad per vertex
            rows = np.zeros((len(points), 4), np.float32)
            rows[:, :3] = points
            position = gltf.accessor(np.zeros((len(points), 3)), view=gltf.view(rows.tobytes(), stride=16),
                                     count=len(points), min=points.min(axis=0).tolist(),
                                     max=points.max(axis=0).tolist())
            primitive = {"attributes": {"POSITION": position},
                         "indices": gltf.accessor(faces.reshape(-1), "uint32")}
        else:
            primitive = gltf.primitive(points, faces)
        gltf.node(gltf.mesh(primitive))
        path = gltf.save(tmp_path / "torus.glb")
    source = load_mesh(str(path))
    arrays = source.indexed_arrays()
    assert arrays is not None
    if kind != "3mf":                               # glTF indices held as int32: half of int64
        assert [piece.dtype for piece in arrays[1]] == [np.dtype(np.int32)]
    gathered = dataclasses.replace(source, read_blocks=lambda: source.read_blocks())
    assert gathered.indexed_arrays() is None
    ours, theirs = analyze(source, "torus"), analyze(gathered, "torus")
    assert (ours.closed, ours.boundary_edges) == (theirs.closed, theirs.boundary_edges) == (False, 3)
    for name in ("volume", "center", "central"):
        assert bits(getattr(ours.moments, name)).tolist() == bits(getattr(theirs.moments, name)).tolist()
        assert bits(getattr(ours.moments.errors, name)).tolist() == bits(getattr(theirs.moments.errors, name)).tolist()
    assert bits([ours.bounds.min, ours.bounds.max]).tolist() == bits([theirs.bounds.min, theirs.bounds.max]).tolist()
    assert_commands_alike(path)
