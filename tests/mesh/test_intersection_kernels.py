"""The self-intersection test's compiled kernels (the fans' certificate and the broad phase in
``p3d_cli.mesh._kernels``) give the numpy code's results.

Each test runs the same input with the kernels and through the numpy code (``kernels.KERNELS``
set to None, or ``P3D_PURE_NUMPY=1`` for whole commands) and compares: the certified vertices
bit for bit, the pairs of overlapping boxes as sets (the compiled grid finds them another way),
the reported intersections and ``p3d check --json`` byte for byte. Skipped where the kernels are
not built, except under CI, whose install compiles them.
"""

from __future__ import annotations

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.kernels import needs_kernels, numpy_road
from helpers.real_meshes import REPO
from helpers.solids import box, indexed
from p3d_cli.geometry.predicates import O3D_BOUND, in_safe_range
from p3d_cli.mesh import kernels
from p3d_cli.mesh.broadphase import box_pairs
from p3d_cli.mesh.compiled_grid import compiled_pairs
from p3d_cli.mesh.intersections import _boxes, self_intersections
from p3d_cli.mesh.stars import _G, certified_vertices
from p3d_cli.mesh.triangle_pairs import uncertified

KERNELS = kernels.KERNELS
pytestmark = needs_kernels

REAL = REPO.parent / "shared" / "real-meshes"


def torus(u: int, v: int, at=(0.0, 0.0, 0.0), scale: float = 1.0):
    """A closed grid torus of ``2 u v`` faces, indexed (the benchmarks' one)."""
    sys.path.insert(0, str(REPO / "benchmarks"))
    try:
        from torus import grid_torus
    finally:
        sys.path.remove(str(REPO / "benchmarks"))
    points, faces = grid_torus(u, v, (0.0, 0.0, 0.0))
    return points * scale + np.array(at), faces


def soup(seed: int, n: int = 400, grid: int = 0):
    """Random triangles of sizes spread over four orders of magnitude (several grid levels),
    some huge, some flat, some of zero extent; on a small integer grid when ``grid`` (exact
    zeros: degenerate faces, coplanar corners)."""
    rng = np.random.default_rng(seed)
    if grid:
        corners = rng.integers(0, grid, size=(n, 3, 3)).astype(np.float64)
    else:
        centre = rng.random((n, 1, 3)) * 10
        size = 10.0 ** rng.uniform(-3, 1, size=(n, 1, 1))
        corners = centre + rng.normal(size=(n, 3, 3)) * size
        corners[: n // 10, :, 2] = corners[: n // 10, :1, 2]           # flat in z
        corners[n // 10: n // 8] = corners[n // 10: n // 8, :1]          # a point
    return indexed(corners)


MESHES = {
    "torus": lambda: torus(40, 20),
    "torus far": lambda: torus(40, 20, at=(1e8, -1e8, 3.0)),
    "torus tiny": lambda: torus(30, 12, scale=1e-30),
    "torus huge": lambda: torus(30, 12, scale=1e30),
    "soup": lambda: soup(1),
    "soup on a grid": lambda: soup(2, n=120, grid=4),
    "two cubes": lambda: indexed(np.concatenate([box([0, 0, 0], [1, 1, 1]), box([0.5, 0.5, 0.5], [2, 2, 2])])),
}


@pytest.mark.parametrize("name", MESHES)
def test_certified_vertices_are_numpys(name):
    points, faces = MESHES[name]()
    safe = in_safe_range(points)
    got = certified_vertices(points, faces, safe)
    assert np.array_equal(got, numpy_road(certified_vertices, points, faces, safe))
    if name.startswith("torus") and safe:
        assert got.all()                           # every fan of a torus is certified


def test_the_certificate_leaves_unsure_corners_to_the_exact_code():
    """On a small integer grid many signs are exactly zero: the compiled pass hands those
    corners back (the exact road decides them), and the result is still the numpy one."""
    points, faces = soup(3, n=300, grid=3)
    normal = np.zeros((len(points), 3))
    KERNELS.star_normals(points, faces, 0, 1 << 15, normal)
    deferred = np.empty(4096, dtype=np.int64)
    good, count = np.ones(len(points), np.uint8), np.zeros(len(points), np.int64)
    unsure = KERNELS.star_signs(points, faces, normal, O3D_BOUND, tuple(_G[0]), tuple(_G[1]), good, count, deferred)
    assert unsure > 0
    assert np.array_equal(certified_vertices(points, faces), numpy_road(certified_vertices, points, faces))


def test_the_normals_are_summed_as_numpy_sums_them():
    """Runs of faces summed apart, then added: more faces than one run (``_STEP``)."""
    points, faces = torus(200, 120)                          # 48,000 faces: two runs
    points = points + np.random.default_rng(4).normal(0, 1e-3, points.shape)
    assert np.array_equal(certified_vertices(points, faces), numpy_road(certified_vertices, points, faces))


def box_pair_set(points, faces, live, certified=None):
    """The numpy road's pairs of faces whose (float32) boxes overlap, as a set."""
    lo, hi = _boxes(points, faces, live)
    pairs = set()
    for i, j in box_pairs(lo, hi):
        if certified is not None:
            keep = uncertified(faces[live], i, j, certified)
            i, j = i[keep], j[keep]
        pairs |= {(min(a, b), max(a, b)) for a, b in zip(live[i].tolist(), live[j].tolist())}
    return pairs


def compiled_pair_list(points, faces, live, certified=None):
    chunks = compiled_pairs(KERNELS, points, faces, live, certified)
    assert chunks is not None
    return [(a, b) for i, j in chunks for a, b in zip(i.tolist(), j.tolist())]


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("window", [7, 1 << 16])
def test_compiled_pairs_are_the_overlapping_boxes(name, window, monkeypatch):
    """Scanned a window of faces at a time (7: many windows, each with the rows it reaches)."""
    import p3d_cli.mesh.compiled_grid as broadphase

    monkeypatch.setattr(broadphase, "WINDOW", window)
    points, faces = MESHES[name]()
    live = np.arange(len(faces), dtype=np.int32)[::-1][::2].copy()       # some faces left out, out of order
    got = compiled_pair_list(points, faces, live)
    assert all(a < b for a, b in got) and len(got) == len(set(got))     # each pair once, smaller first
    assert set(got) == box_pair_set(points, faces, live)
    certified = certified_vertices(points, faces, in_safe_range(points))
    assert set(compiled_pair_list(points, faces, live, certified)) == box_pair_set(points, faces, live, certified)


@given(st.integers(0, 2**32 - 1), st.integers(2, 200), st.sampled_from([0, 2, 5]))
def test_compiled_pairs_on_random_soups(seed, n, grid):
    points, faces = soup(seed, n, grid)
    live = np.arange(len(faces), dtype=np.int64)
    got = compiled_pair_list(points, faces, live)
    assert len(got) == len(set(got)) and set(got) == box_pair_set(points, faces, live)


def test_a_crowded_cell_grows_the_output():
    """One face meeting more pairs than the output holds: the caller gives more room."""
    import p3d_cli.mesh.compiled_grid as broadphase

    shift = np.zeros((300, 1, 3))
    shift[:, 0, 0] = np.linspace(0, 1e-3, 300)                 # along the triangle's plane
    points, faces = indexed(np.repeat(box([0, 0, 0], [1, 1, 1])[:1], 300, axis=0) + shift)
    live = np.arange(len(faces), dtype=np.int32)
    saved = broadphase.COMPILED_PAIRS
    broadphase.COMPILED_PAIRS = 7
    try:
        got = compiled_pair_list(points, faces, live)
    finally:
        broadphase.COMPILED_PAIRS = saved
    assert len(got) == len(set(got)) == 300 * 299 // 2


def test_parts_too_far_apart_for_the_keys_take_the_numpy_road():
    parts = [box([0, 0, 0], [2.0 ** -40] * 3), box([2.0 ** 30] * 3, [2.0 ** 30 + 1] * 3)]
    points, faces = indexed(np.concatenate(parts))
    assert compiled_pairs(KERNELS, points, faces, np.arange(len(faces)), None) is None
    assert self_intersections(points, faces).count == 0


def results(points, faces, fans):
    r = self_intersections(points, faces, fans=fans)
    return r.count, r.by_kind, r.pairs.tolist(), r.kinds, repr(r.samples), r.faces_tested


@pytest.mark.parametrize("name", MESHES)
@pytest.mark.parametrize("fans", [False, True])
def test_self_intersections_are_numpys(name, fans):
    points, faces = MESHES[name]()
    assert results(points, faces, fans) == numpy_road(results, points, faces, fans)


def test_overlapping_tori_are_numpys():
    p, f = torus(60, 30)
    q, g = torus(50, 25, at=(1.3, 0.2, 0.1))
    points, faces = np.concatenate([p, q]), np.concatenate([f, g + len(p)])
    got = results(points, faces, True)
    assert got[0] > 0
    assert got == numpy_road(results, points, faces, True) == results(points, faces, False)


def test_bad_arguments_raise():
    keys = np.arange(3, dtype=np.uint64)
    level = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (4, 4, 4), 4, (1, 1, 1))
    out = np.zeros(8, dtype=np.int64)

    def pairs(entries, level=level, window=0):
        return KERNELS.grid_pairs(keys, entries, window, None, np.arange(3), level, None, None, None, None, 0, 3, out,
                                  out.copy())

    assert pairs(np.zeros((3, 36), np.uint8)) == (3, 3)           # three equal boxes at the origin
    with pytest.raises(ValueError):                              # entries beyond the keys
        pairs(np.zeros((4, 36), np.uint8))
    with pytest.raises(ValueError):                              # a scan past the window's entries
        pairs(np.zeros((2, 36), np.uint8))
    with pytest.raises(ValueError):                              # a lookup needs the level's every entry
        KERNELS.grid_pairs(keys, np.zeros((2, 36), np.uint8), 0, None, np.arange(3), level, keys,
                           np.zeros((3, 36), np.uint8), None, np.arange(3), 0, 3, out, out.copy())
    with pytest.raises(ValueError):                              # keys of 70 bits
        pairs(np.zeros((3, 36), np.uint8), ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), (30, 30, 6), 4, (1, 1, 1)))
    with pytest.raises(ValueError):                              # a vertex id out of range
        KERNELS.star_normals(np.zeros((3, 3)), np.array([[0, 1, 3]]), 0, 8, np.zeros((3, 3)))
    with pytest.raises(TypeError):
        KERNELS.star_normals(np.zeros((3, 3), np.float32), np.array([[0, 1, 2]]), 0, 8, np.zeros((3, 3)))


def real_meshes():
    if not REAL.is_dir():
        return []
    return sorted(p for p in REAL.iterdir() if p.suffix.lower() in {".stl", ".ply", ".obj", ".off"})


def test_real_meshes_are_here_under_ci():
    if os.environ.get("CI") == "true":
        assert real_meshes(), f"{REAL} is missing"


@pytest.mark.parametrize("path", real_meshes(), ids=lambda p: p.name)
def test_real_meshes_alike(path):
    """``p3d.self_intersections`` on every real mesh, with the kernels and without."""
    from p3d_cli.measure.measurements import self_intersections as api

    def found():
        r = api(str(path))
        return r.count, r.by_kind, r.pairs.tolist(), r.kinds, repr(r.samples), r.faces_tested

    assert found() == numpy_road(found)


def check_files():
    """The sample meshes and the smaller real ones (the command's whole road, in a child)."""
    files = sorted((REPO / "sample_meshes").glob("*.[so][tfb][lfj]"))
    return files + [p for p in real_meshes() if p.stat().st_size < 200_000]


def test_check_json_alike(tmp_path):
    """``p3d check --json``, the self-intersection test included, byte for byte with the kernels
    and without: on the sample meshes, some real ones, and self-intersecting files."""

    p, f = torus(40, 20)
    q, g = torus(30, 15, at=(1.3, 0.2, 0.1))
    crossing = tmp_path / "crossing_tori.stl"
    cubes = tmp_path / "overlapping_cubes.stl"
    write(crossing, np.concatenate([p[f], q[g]]))
    write(cubes, np.concatenate([box([0, 0, 0], [1, 1, 1]), box([0.5, 0.5, 0.5], [2, 2, 2])]))
    files = [str(p) for p in check_files() + [crossing, cubes]]
    outputs = []
    for pure in ("0", "1"):                         # every file in one batch per road
        env = dict(os.environ, P3D_PURE_NUMPY=pure)
        done = subprocess.run([sys.executable, "-m", "p3d_cli", "check", *files, "--json"], env=env,
                              capture_output=True, check=False)
        outputs.append((done.returncode, done.stdout, done.stderr))
    assert outputs[0] == outputs[1]
    assert outputs[0][1].count(b"no-self-intersection") >= len(files)
    assert outputs[0][0] != 0                       # the tori and the cubes cross themselves


def write(path, triangles) -> None:
    records = np.zeros(len(triangles), np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)),
                                                 ("attr", "<u2")]))
    records["corners"] = triangles
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + np.uint32(len(triangles)).tobytes() + records.tobytes())


def paired_oracle(faces, m):
    """``paired_vertices`` the slow way: per vertex, its faces' next and previous corners."""
    nexts = [[] for _ in range(m)]
    prevs = [[] for _ in range(m)]
    for f in np.asarray(faces).tolist():
        for k in range(3):
            nexts[f[k]].append(f[(k + 1) % 3])
            prevs[f[k]].append(f[(k + 2) % 3])
    return np.array([len(set(n)) == len(n) and sorted(n) == sorted(p) and v not in n
                     for v, (n, p) in enumerate(zip(nexts, prevs))])


def open_torus(holes: int = 7):
    points, faces = torus(30, 14)
    return points, np.delete(faces, np.arange(0, len(faces), len(faces) // holes), axis=0)


@pytest.mark.parametrize("case", ["open torus", "soup on a grid", "bowtie", "turned face", "doubled face"])
def test_paired_vertices_are_the_oracles(case):
    from p3d_cli.mesh.stars import paired_vertices

    if case == "open torus":
        points, faces = open_torus()
    elif case == "soup on a grid":
        points, faces = soup(5, n=200, grid=3)
    else:
        points, faces = torus(12, 6)
        if case == "bowtie":                 # a second torus sharing one vertex
            faces = np.concatenate([faces, np.where(faces == 0, 0, faces + len(points))])
            points = np.concatenate([points, points + [8.0, 0.0, 0.0]])
        elif case == "turned face":
            faces = faces.copy()
            faces[5] = faces[5, ::-1]
        else:
            faces = np.concatenate([faces, faces[:1]])
    got = paired_vertices(faces, len(points))
    assert np.array_equal(got, paired_oracle(faces, len(points)))
    if case == "bowtie":
        # Two closed fans at vertex 0: its edges pair up, and the count (two wraps) refuses it.
        assert got.all()
        assert not certified_vertices(points, faces)[0]
    elif case != "soup on a grid":
        assert 0 < got.sum() < len(points)


@pytest.mark.parametrize("holes", [1, 7, 40])
def test_open_meshes_certify_their_inner_fans_and_find_the_same_pairs(holes):
    """An open torus, alone and pushed through a closed one: the fans away from the holes are
    certified (fewer pairs to test), and the pairs found are those of the pair test alone and
    of the numpy road."""
    from p3d_cli.mesh.stars import paired_vertices

    points, faces = open_torus(holes)
    paired = paired_vertices(faces, len(points))
    assert (certified_vertices(points, faces) & paired).sum() > len(points) // 2
    q, g = torus(20, 10, at=(1.2, 0.3, 0.2))
    both = np.concatenate([points, q]), np.concatenate([faces, g + len(points)])
    for p, f in ((points, faces), both):
        got = results(p, f, False)
        assert got == numpy_road(results, p, f, False)
    live = np.arange(len(both[1]))
    all_pairs = compiled_pair_list(*both, live)
    cert = certified_vertices(*both) & paired_vertices(both[1], len(both[0]))
    assert len(compiled_pair_list(*both, live, cert)) < len(all_pairs) / 3
    assert results(*both, False)[0] > 0


def discs_over_torus():
    """A torus crossed by three flat discs, each a fan of 198 long slivers: the slivers' boxes
    make several coarse grid levels whose one box around them all holds the whole torus."""
    points, faces = torus(200, 40)
    triangles = [points[faces]]
    angles = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    for z in (-0.5, 0.1, 0.7):
        rim = np.stack([3.5 * np.cos(angles), 3.5 * np.sin(angles), np.full(200, z)], axis=1)
        triangles.append(np.stack([np.repeat(rim[:1], 198, axis=0), rim[1:-1], rim[2:]], axis=1))
    return indexed(np.concatenate(triangles))


@pytest.mark.parametrize("window", [7, 1 << 16])
def test_compiled_pairs_of_sliver_discs_are_the_overlapping_boxes(window, monkeypatch):
    """The coarse levels' probes (the finer entries kept from their own scan, the faces off
    the levels' shadows passed over) find every pair of overlapping boxes, each once."""
    import p3d_cli.mesh.compiled_grid as broadphase

    monkeypatch.setattr(broadphase, "WINDOW", window)
    points, faces = discs_over_torus()
    live = np.arange(len(faces), dtype=np.int32)
    got = compiled_pair_list(points, faces, live)
    assert all(a < b for a, b in got) and len(got) == len(set(got))
    assert set(got) == box_pair_set(points, faces, live)


@given(st.lists(st.tuples(st.floats(-1e3, 1e3, width=32), st.floats(0, 1e3, width=32)), min_size=1, max_size=30),
       st.lists(st.tuples(st.floats(-2e3, 2e3, width=32), st.floats(0, 1e3, width=32)), min_size=1, max_size=30))
def test_a_shadow_meets_every_extent_that_meets_one_of_its_own(own, asked):
    """Extents ``(start, length)``, float32 as the grid's boxes: ``meets`` is never False for
    an extent that shares a point with one of the shadow's (it may be True for others)."""
    from p3d_cli.mesh.compiled_grid import Shadow

    lo = np.array([s for s, _ in own], dtype=np.float32)
    hi = (lo + np.array([w for _, w in own], dtype=np.float32)).astype(np.float32)
    shadow = Shadow(lo, hi, float(lo.min()), float(hi.max()))
    q_lo = np.array([s for s, _ in asked], dtype=np.float32)
    q_hi = (q_lo + np.array([w for _, w in asked], dtype=np.float32)).astype(np.float32)
    meets = shadow.meets(q_lo, q_hi)
    truth = ((q_lo[:, None] <= hi[None, :]) & (lo[None, :] <= q_hi[:, None])).any(axis=1)
    assert not (truth & ~meets).any()


def test_a_shadow_of_a_point_or_of_a_span_beyond_its_arithmetic_is_one_bin():
    """Every extent meets a shadow whose span is zero, overflows, or is too small to invert;
    extents far beyond a shadow's span are clipped into its end bins, without warnings."""
    from p3d_cli.mesh.compiled_grid import Shadow

    for lo, hi in (([1.0], [1.0]), ([-1e308], [1e308]), ([0.0, 1e-310], [1e-310, 2e-310])):
        shadow = Shadow(np.array(lo), np.array(hi), min(lo), max(hi))
        assert shadow.meets(np.array([-5.0, 0.0, 7.0]), np.array([-4.0, 0.0, 8.0])).all()
    shadow = Shadow(np.array([0.0, 10.0]), np.array([1.0, 11.0]), 0.0, 11.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        got = shadow.meets(np.array([2.0, 0.5, -1e308, 1.5]), np.array([9.0, 0.7, 1e308, 1.6]))
    assert got.tolist() == [False, True, True, False]
