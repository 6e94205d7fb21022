"""Self-intersections of whole meshes: exact answers on configurations known by construction."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.solids import box, grid, indexed, octahedron
from helpers.triangle_oracle import CONTACT, CROSSING, FOLD, OVERLAP, classify as oracle
from p3d_cli.mesh.broadphase import box_pairs
from p3d_cli.mesh.intersections import crowded_edges, self_intersections
from p3d_cli.mesh.topology import topology


def found(triangles):
    """The self-intersections, by the pair test alone and, for a closed manifold mesh, with
    the fans' certificate too (p3d_cli.mesh.stars): both must give the same pairs."""
    points, faces = indexed(triangles)
    result = self_intersections(points, faces)
    report = topology(np.asarray(triangles, dtype=float))
    if report.closed and report.nonmanifold_vertices == 0:
        fast = self_intersections(points, faces, fans=True)
        assert fast.pairs.tolist() == result.pairs.tolist() and fast.kinds == result.kinds
    return result


def test_a_closed_cube_does_not_intersect_itself():
    assert found(box([0, 0, 0], [1, 1, 1])).count == 0


@pytest.mark.parametrize("offset", [0.0, 1e8, -3e12])
@pytest.mark.parametrize("shift, diagonals", [
    ((1, 0, 0), None),                                 # sharing a face, triangulated alike
    ((1, 0, 0), [True, False, True, True, False, True]),  # ... and differently
    ((1, 1, 0), None),                                 # sharing an edge
    ((1, 1, 1), None),                                 # sharing a vertex
    ((1, 0.5, 0.25), None),                            # pressed together over part of a face
])
def test_cubes_that_touch_never_intersect(shift, diagonals, offset):
    a = box([0, 0, 0], [1, 1, 1])
    b = box(shift, np.add(shift, 1), diagonals)
    assert found(np.concatenate([a, b]) + offset).count == 0


@pytest.mark.parametrize("size, offset", [(1.0, 0.0), (1e3, 1e8), (2.0 ** -30, 0.0), (1e6, -1e8)])
def test_cubes_overlapping_by_a_sliver_of_1e_9_of_their_size_intersect(size, offset):
    sliver = size * 1e-9
    a = box([0, 0, 0], [size, size, size]) + offset
    b = box([size - sliver, 0, 0], [2 * size - sliver, size, size]) + offset
    assert (b[:, :, 0].min() - offset) < size          # the sliver survives rounding
    result = found(np.concatenate([a, b]))
    assert result.count > 0 and set(result.by_kind) == {"crossing", "overlap", "fold"}
    # The faces that meet are the first cube's +x side and the second's -x side and their
    # neighbours; every sample point lies in the sliver.
    for sample in result.samples:
        assert size - 2 * sliver <= sample.point[0] - offset <= size + sliver


def test_overlapping_cubes_report_the_exact_pairs_and_points():
    result = found(np.concatenate([box([0, 0, 0], [2, 2, 2]), box([1, 1, 1], [3, 3, 3])]))
    assert result.count == 6 and result.by_kind == {"crossing": 6, "overlap": 0, "fold": 0}
    for sample in result.samples:                       # on the two boxes' common boundary
        p = np.array(sample.point)
        assert ((p >= 1) & (p <= 2)).all() and ((p == 1) | (p == 2)).sum() >= 2


def test_coplanar_overlapping_triangles():
    t = np.array([[[0, 0, 0], [4, 0, 0], [0, 4, 0]], [[1, 1, 0], [5, 1, 0], [1, 5, 0]]], dtype=float)
    result = found(t)
    assert result.count == 1 and result.samples[0].kind == "overlap"
    assert found(np.stack([t[0], t[1][::-1]])).count == 0      # facing apart: pressed together


def test_an_edge_lying_in_a_face_pierces_it():
    """An octahedron whose equator lies exactly in a box's top face: no two faces cross in
    their interiors, every contact is an edge lying in the face, and still the surfaces cross."""
    slab = box([-2, -2, -1], [2, 2, 0])
    result = found(np.concatenate([slab, octahedron([0, 0, 0], 1)]))
    assert result.count > 0 and result.by_kind["crossing"] == result.count
    assert all(s.point[2] == 0 for s in result.samples)
    # Resting on the face (touching at a vertex), or lifted: no intersection.
    assert found(np.concatenate([slab, octahedron([0, 0, 1], 1)])).count == 0
    assert found(np.concatenate([slab, octahedron([0, 0, 1.5], 1)])).count == 0


def test_a_triangle_piercing_another_through_its_edge_published_example():
    """magpylib issue #589's published mesh: a cube with a spike from its top face through the
    bottom face (vertex 8 at z = -3). Its own coordinates and faces."""
    x = [-1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, 0.5]
    y = [-1.0, 1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, 0.1]
    z = [-1.0, -1.0, -1.0, -1.0, 1.0, 1.0, 1.0, 1.0, -3.0]
    i = [7, 0, 0, 0, 2, 6, 4, 0, 3, 7, 4, 5, 6, 7]
    j = [0, 7, 1, 2, 1, 2, 5, 5, 2, 2, 5, 6, 7, 4]
    k = [3, 4, 2, 3, 5, 5, 0, 1, 7, 6, 8, 8, 8, 8]
    points = np.array([x, y, z]).T
    result = self_intersections(points, np.array([i, j, k]).T)
    assert result.count > 0
    assert all(s.point[2] == -1.0 for s in result.samples)     # where the spike crosses the bottom


def test_a_twice_subdivided_triangle_has_no_intersection_published_example():
    """libigl issue #2381's published mesh (15 vertices, 16 coplanar faces), which its fast
    test reported as 5 intersecting pairs."""
    V = np.array([
        [0.280039012432098, 0.82766300439834595, 0.46377500891685502],
        [0.33890101313590998, 0.78804200887680098, 0.48812699317932101],
        [0.31805300712585399, 0.76836401224136397, 0.49308800697326699],
        [0.30947001278400399, 0.80785250663757346, 0.47595100104808802],
        [0.299046009778976, 0.79801350831985496, 0.47843150794506101],
        [0.32847701013088199, 0.77820301055908248, 0.490607500076294],
        [0.29475451260805097, 0.81775775551795971, 0.46986300498247152],
        [0.28954251110553697, 0.81283825635910045, 0.47110325843095802],
        [0.32418551295995701, 0.79794725775718722, 0.48203899711370451],
        [0.33368901163339598, 0.78312250971794173, 0.48936724662780751],
        [0.30854950845241502, 0.78318876028060946, 0.485759757459164],
        [0.32326500862836799, 0.77328351140022322, 0.4918477535247805],
        [0.30425801128148999, 0.80293300747871421, 0.47719125449657451],
        [0.31897351145744302, 0.79302775859832797, 0.48327925056219101],
        [0.31376150995492902, 0.78810825943946872, 0.4845195040106775]])
    F = np.array([[2, 11, 10], [1, 8, 9], [0, 7, 6], [3, 12, 13], [5, 14, 11], [3, 13, 8], [4, 12, 7],
                  [4, 14, 12], [4, 10, 14], [5, 9, 13], [3, 6, 12], [5, 13, 14], [14, 10, 11], [13, 9, 8],
                  [12, 6, 7], [14, 13, 12]])
    assert self_intersections(V, F).count == 0


def test_a_closed_scan_pushed_through_itself():
    """A closed sphere whose north pole is pushed in: a dent (inside the body) is a valid
    surface, through the south cap it crosses itself. The fans around the pole are certified
    in neither case (their faces turn over), every other fan is, and both ways agree."""
    sphere = _sphere(24)
    assert found(sphere).count == 0
    pole = np.isclose(sphere[:, :, 2], 1.0)
    dented = sphere.copy()
    dented[pole] = [0.0, 0.0, -0.5]
    assert found(dented).count == 0
    through = sphere.copy()
    through[pole] = [0.0, 0.0, -1.5]
    result = found(through)
    assert result.count > 0 and all(s.point[2] < -0.9 for s in result.samples)


def _sphere(n: int) -> np.ndarray:
    """A closed UV sphere of radius 1, wound outwards, poles on the z axis."""
    theta = np.linspace(0, np.pi, n + 1)[1:-1]
    phi = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    ring = np.stack([np.sin(theta)[:, None] * np.cos(phi), np.sin(theta)[:, None] * np.sin(phi),
                     -np.cos(theta)[:, None] * np.ones_like(phi)], axis=-1)
    south, north = np.array([0, 0, -1.0]), np.array([0, 0, 1.0])
    tris = []
    m = len(phi)
    for j in range(m):
        tris.append([south, ring[0, (j + 1) % m], ring[0, j]])
        tris.append([north, ring[-1, j], ring[-1, (j + 1) % m]])
    for i in range(len(theta) - 1):
        for j in range(m):
            a, b, c, d = ring[i, j], ring[i, (j + 1) % m], ring[i + 1, (j + 1) % m], ring[i + 1, j]
            tris += [[a, b, c], [a, c, d]]
    return np.array(tris)


def test_a_fold_in_a_scan():
    """A scanned height field whose middle row of vertices is pushed past the next row: the
    strip of faces between them turns over and lies across its neighbours."""
    points, faces = grid(6, lambda x, y: 0.1 * np.sin(x) * np.cos(y))
    assert self_intersections(points, faces).count == 0
    folded = points.copy()
    row = np.isclose(folded[:, 0], 3)
    folded[row, 0] = 4.5                                 # over the next row at x = 4
    result = self_intersections(folded, faces)
    assert result.count > 0


def test_adjacent_faces_folded_flat_onto_each_other():
    """A flat grid with one vertex moved across its neighbours within the plane: the faces
    around it turn over and lie on their neighbours across shared edges: folds."""
    points, faces = grid(4)
    moved = points.copy()
    centre = np.flatnonzero((moved[:, 0] == 2) & (moved[:, 1] == 2))[0]
    moved[centre, :2] = [3.5, 2.25]
    result = self_intersections(moved, faces)
    assert result.by_kind["fold"] > 0 and result.count >= result.by_kind["fold"]
    for sample in result.samples:
        assert sample.point[2] == 0


def test_degenerate_faces_take_no_part():
    cube = box([0, 0, 0], [1, 1, 1])
    sliver = np.array([[[0.5, 0.5, -1], [0.5, 0.5, 2], [0.5, 0.5, 0.5]]])   # collinear: zero area
    result = found(np.concatenate([cube, sliver]))
    assert result.count == 0 and result.faces_tested == 12


@st.composite
def two_boxes(draw):
    """Two boxes on an integer grid, each triangulated with its own diagonals, under an exact
    signed axis permutation, scale and offset."""
    lo_a = np.array(draw(st.lists(st.integers(0, 3), min_size=3, max_size=3)))
    lo_b = np.array(draw(st.lists(st.integers(0, 3), min_size=3, max_size=3)))
    hi_a = lo_a + np.array(draw(st.lists(st.integers(1, 3), min_size=3, max_size=3)))
    hi_b = lo_b + np.array(draw(st.lists(st.integers(1, 3), min_size=3, max_size=3)))
    diag = [draw(st.lists(st.booleans(), min_size=6, max_size=6)) for _ in range(2)]
    if draw(st.booleans()):
        lo_b, hi_b = lo_a, hi_a                        # the same box again, maybe triangulated alike
    triangles = np.concatenate([box(lo_a, hi_a, diag[0]), box(lo_b, hi_b, diag[1])])
    axes = draw(st.permutations(range(3)))
    signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3)))
    offset = draw(st.sampled_from([0.0, 1e8, -2.0 ** 45]))
    # Exact placement: far from the origin the grid step must stay above the coordinates' ulp.
    scale = 2.0 ** draw(st.integers(-30 if offset == 0 else -5, 30))
    placed = triangles[:, :, list(axes)] * signs * scale + offset
    return (lo_a, hi_a, lo_b, hi_b, diag[0] == diag[1]), placed


@given(two_boxes())
def test_two_boxes_intersect_exactly_when_they_share_volume_without_nesting(case):
    """Truth by construction: two boxes wound alike share volume (counted twice) unless they
    are apart or touching; they intersect then, unless one lies strictly inside the other
    (nested: the nesting check's) or both are the same twelve faces (the duplicate check's)."""
    (lo_a, hi_a, lo_b, hi_b, alike), triangles = case
    overlap = np.minimum(hi_a, hi_b) - np.maximum(lo_a, lo_b)
    strictly_inside = (((lo_a > lo_b) & (hi_a < hi_b)).all() or ((lo_b > lo_a) & (hi_b < hi_a)).all())
    duplicates = (lo_a == lo_b).all() and (hi_a == hi_b).all() and alike
    expected = bool((overlap > 0).all()) and not strictly_inside and not duplicates
    assert (found(triangles).count > 0) == expected


def test_every_pair_matches_the_rational_oracle_on_random_solids():
    """Random octahedra and boxes on a coarse grid (touching, sharing, crossing): every pair
    the oracle calls a crossing, overlap or fold is found, and every pair found is one of
    those or a touching contact whose surroundings cross."""
    rng = np.random.default_rng(5)
    for _ in range(12):
        parts = []
        for _ in range(3):
            c = rng.integers(0, 4, 3).astype(float)
            parts.append(octahedron(c, float(rng.integers(1, 3))) if rng.random() < 0.5
                         else box(c, c + rng.integers(1, 3, 3)))
        triangles = np.concatenate(parts)
        points, faces = indexed(triangles)
        result = self_intersections(points, faces)
        expected, contacts = set(), set()
        for i in range(len(faces)):
            for j in range(i + 1, len(faces)):
                kind = oracle(points[faces[i]].tolist(), points[faces[j]].tolist())
                if kind in (CROSSING, OVERLAP, FOLD):
                    expected.add((i, j))
                elif kind == CONTACT:
                    contacts.add((i, j))
        got = {tuple(p) for p in result.pairs.tolist()}
        # Faces lying on each other across an edge more faces use are two sheets pressed
        # together, not a fold (two boxes sharing a face, triangulated differently).
        crowded = {tuple(e) for e in crowded_edges(faces).tolist()}
        pressed = {p for p in expected if _shared(faces, p) in crowded}
        assert expected - pressed <= got
        assert got - expected <= contacts | {p for p in got if len(_shared(faces, p)) == 2}


def _shared(faces, pair) -> tuple:
    return tuple(sorted(set(faces[pair[0]].tolist()) & set(faces[pair[1]].tolist())))


def test_box_pairs_are_every_overlapping_pair_once():
    rng = np.random.default_rng(0)
    for trial in range(20):
        n = int(rng.integers(2, 300))
        centre = rng.random((n, 3)) * rng.choice([1, 10, 100])
        extent = rng.random((n, 3)) ** rng.choice([1, 3, 6]) * rng.choice([0.1, 1, 5])
        if trial % 5 == 0:
            extent[:, 2] = 0                                  # flat boxes
        lo, hi = (centre - extent).astype(np.float32), (centre + extent).astype(np.float32)
        got = [tuple(sorted(p)) for i, j in box_pairs(lo, hi) for p in zip(i.tolist(), j.tolist())]
        assert len(got) == len(set(got))
        expected = {(i, j) for i in range(n) for j in range(i + 1, n)
                    if (lo[i] <= hi[j]).all() and (lo[j] <= hi[i]).all()}
        assert set(got) == expected


def test_certified_fans_have_no_crossing_pair_and_folded_fans_are_not_certified():
    """The fans' certificate against the rational oracle: on a sphere whose vertices are
    shaken hard (some fans fold), every pair of faces around a certified vertex meets only
    as neighbours do, and fans that fold are left to the pair test."""
    from p3d_cli.mesh.stars import certified_vertices

    rng = np.random.default_rng(2)
    points, faces = indexed(_sphere(8))
    shaken = points + rng.normal(0, 0.12, points.shape)
    certified = certified_vertices(shaken, faces)
    assert 0 < certified.sum() < len(points)                  # both kinds occur
    for v in range(len(points)):
        around = np.flatnonzero((faces == v).any(axis=1))
        bad = any(oracle(shaken[faces[a]].tolist(), shaken[faces[b]].tolist()) in (CROSSING, OVERLAP, FOLD,
                                                                                    CONTACT)
                  for k, a in enumerate(around) for b in around[k + 1:])
        if certified[v]:
            assert not bad


@pytest.mark.parametrize("far", [2.0 ** 50, 1e100, 1e300, 1e-300])
def test_parts_far_apart_huge_or_tiny(far):
    """A tiny box at the origin and two crossing boxes at ``far``: the grid is too wide for one
    key (its cells are ranked), float32 boxes would overflow or underflow (they are scaled),
    products overflow (the integers decide). The same six pairs are found at every scale."""
    import warnings

    parts = [box([0, 0, 0], [far * 2 ** -60] * 3), box([far] * 3, [far * (1 + 2 ** -40)] * 3),
             box([far * (1 + 2 ** -41)] * 3, [far * (1 + 2 ** -39)] * 3)]
    points, faces = indexed(np.concatenate(parts))
    for fans in (False, True):
        with warnings.catch_warnings():
            warnings.simplefilter("error")             # nothing of the test over- or underflows
            result = self_intersections(points, faces, fans=fans)
        assert result.count == 6 and result.by_kind["crossing"] == 6


@pytest.mark.parametrize("offset", [0, 1 << 33])          # vertex ids past 2**31 take the rows' road
def test_crowded_edges_are_the_counted_edges_in_order(offset):
    """``crowded_edges``: the edges of more than two faces, as sorted ``(lo, hi)`` rows in
    ascending order, counted here one edge at a time."""
    from collections import Counter

    rng = np.random.default_rng(3)
    for n, m in [(1, 3), (40, 6), (3000, 60), (5000, 4000)]:
        faces = rng.integers(0, m, size=(n, 3)).astype(np.int64) + offset
        counted = Counter(tuple(sorted((int(f[k]), int(f[(k + 1) % 3])))) for f in faces for k in range(3))
        want = sorted(e for e, c in counted.items() if c > 2)
        got = crowded_edges(faces.astype(np.int32) if offset == 0 else faces)
        assert got.dtype == np.int64 and got.shape == (len(want), 2)
        assert [tuple(e) for e in got.tolist()] == want
    assert crowded_edges(np.zeros((0, 3), dtype=np.int64)).shape == (0, 2)
