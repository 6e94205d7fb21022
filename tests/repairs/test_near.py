"""The faces near new faces (``p3d_cli.repairs.near``) and the fillings' crossing test built on
them (``p3d_cli.repairs.solidity.crossing_fillings``): never missing a face, and deciding as
the whole mesh's self-intersection test does."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np
import pytest

from helpers.kernels import needs_kernels
from p3d_cli.mesh import kernels
from p3d_cli.mesh.intersections import self_intersections
from p3d_cli.mesh.verdicts import CHECKS
from p3d_cli.repairs import near, pipeline
from p3d_cli.repairs.near import near_pairs
from p3d_cli.repairs.pipeline import checked
from p3d_cli.repairs.solidity import PROBES, SCREENED, crossing_fillings


def meets_exactly(triangle: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    """The separating-axis test of a triangle and a closed box in rational arithmetic."""
    c = [(Fraction(a) + Fraction(b)) / 2 for a, b in zip(lo.tolist(), hi.tolist())]
    h = [(Fraction(b) - Fraction(a)) / 2 for a, b in zip(lo.tolist(), hi.tolist())]
    v = [[Fraction(x) - c[i] for i, x in enumerate(p)] for p in triangle.tolist()]
    e = [[v[(k + 1) % 3][i] - v[k][i] for i in range(3)] for k in range(3)]

    def cross(a, b):
        return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])

    units = [(1, 0, 0), (0, 1, 0), (0, 0, 1)]
    axes = units + [cross(e[0], e[1])] + [cross(edge, u) for edge in e for u in units]
    for a in axes:
        p = [sum(a[i] * x[i] for i in range(3)) for x in v]
        r = sum(abs(a[i]) * h[i] for i in range(3))
        if min(p) > r or max(p) < -r:
            return False
    return True


def soup(seed: int, n: int = 300):
    """Small triangles spread in a box, some long slivers among them, some turned to lines."""
    rng = np.random.default_rng(seed)
    base = rng.random((n, 3)) * 10 + rng.normal(size=3) * 10.0 ** rng.integers(0, 6)
    points = np.concatenate([base, base + rng.normal(size=(n, 3)) * 0.5, base + rng.normal(size=(n, 3)) * 0.5])
    faces = np.stack([np.arange(n), np.arange(n) + n, np.arange(n) + 2 * n], axis=1)
    points[faces[:20, 1]] = points[faces[:20, 0]] + rng.normal(size=(20, 3)) * 8
    if seed % 2:
        points[faces[40:60, 2]] = points[faces[40:60, 0]]
    return points, faces


@pytest.mark.parametrize("seed", range(4))
def test_every_face_whose_box_meets_a_query_triangle_is_paired(seed):
    points, faces = soup(seed)
    query = np.arange(0, 25)
    group = np.full(len(faces), -1)
    group[:10] = 0                      # the first ten are one filling: not paired together
    at, face = near_pairs(points, faces, query, group)
    got = set(zip(at.tolist(), face.tolist()))
    want = set()
    for k, q in enumerate(query.tolist()):
        for f in range(len(faces)):
            if f == q or (group[f] >= 0 and group[f] == group[q]):
                continue
            corners = points[faces[f]]
            if meets_exactly(points[faces[q]], corners.min(axis=0), corners.max(axis=0)):
                want.add((k, f))
    assert want <= got
    assert all(f != query[k] and not (group[f] >= 0 and group[f] == group[query[k]]) for k, f in got)
    # The tree's margin adds no more than a few faces beyond the exact answer.
    assert len(got - want) <= 0.05 * len(want) + 2


def holed_torus(u: int, v: int, rows: tuple[int, ...]):
    """A grid torus with whole rows of quads removed, and each of the rings left open filled
    with a fan from its first corner (what ear clipping gives a convex loop): flat discs, some
    through the far side of the tube, some in the torus's hole."""
    i, j = np.meshgrid(np.arange(u), np.arange(v), indexing="ij")
    theta, phi = 2 * np.pi * i / u, 2 * np.pi * j / v
    ring = 3.0 + np.cos(phi)
    points = np.stack([ring * np.cos(theta), ring * np.sin(theta), np.sin(phi)], axis=-1).reshape(-1, 3)
    points = points.astype(np.float32).astype(np.float64)
    a = (i * v + j)
    b = ((i + 1) % u) * v + j
    c = ((i + 1) % u) * v + (j + 1) % v
    d = i * v + (j + 1) % v
    keep = ~np.isin(j, rows).ravel()
    faces = np.concatenate([np.stack([a.ravel(), b.ravel(), c.ravel()], 1)[keep],
                            np.stack([a.ravel(), c.ravel(), d.ravel()], 1)[keep]])
    fillings, start = [], len(faces)
    fans = []
    for row in rows:
        for at, up in ((row, False), ((row + 1) % v, True)):
            loop = np.arange(u) * v + at
            loop = loop if up else loop[::-1]
            fan = np.stack([np.full(u - 2, loop[0]), loop[1:-1], loop[2:]], axis=1)
            fans.append(fan)
            fillings.append(np.arange(start, start + len(fan)))
            start += len(fan)
    return points, np.concatenate([faces] + fans), fillings


def whole_test(points, faces, fillings) -> np.ndarray:
    """The oracle: the whole mesh's self-intersection test, a filling refused when a reported
    pair has one of its faces."""
    found = self_intersections(points, faces)
    hit = set(found.pairs.ravel().tolist())
    return np.array([bool(hit & set(f.tolist())) for f in fillings])


@pytest.mark.parametrize("u, v, rows", [(40, 10, (0, 2, 4, 6, 8)), (36, 12, (0, 3, 6)), (60, 20, (1, 7, 13))])
def test_fillings_of_a_holed_torus_are_refused_as_the_whole_test_does(u, v, rows):
    """Discs through the tube touch rings of vertices lying exactly in their planes (contacts
    along lines, decided by the probe) or cross it (decided by the screen); discs in the
    torus's hole cross nothing."""
    points, faces, fillings = holed_torus(u, v, rows)
    assert min(len(f) for f in fillings) >= SCREENED > PROBES
    want = whole_test(points, faces, fillings)
    assert want.any() and not want.all()
    assert crossing_fillings(points, faces, fillings).tolist() == want.tolist()


@pytest.mark.parametrize("seed", range(4))
def test_fillings_in_a_soup_are_refused_as_the_whole_test_does(seed):
    """Fans of many faces and single faces among random triangles."""
    rng = np.random.default_rng(seed)
    points, faces = soup(seed, 200)
    start, fillings, extra = len(points), [], []
    for _ in range(6):
        size = int(rng.choice([1, 2, SCREENED, 40]))
        centre = rng.random(3) * 10
        angle = np.linspace(0, 2 * np.pi, size + 2, endpoint=False)
        rim = centre + rng.random() * 3 * np.stack([np.cos(angle), np.sin(angle), 0 * angle], 1)
        rim = rim @ np.linalg.qr(rng.normal(size=(3, 3)))[0]
        ids = start + np.arange(size + 2)
        start += size + 2
        points = np.concatenate([points, rim])
        fan = np.stack([np.full(size, ids[0]), ids[1:-1], ids[2:]], axis=1)
        fillings.append(len(faces) + sum(len(e) for e in extra) + np.arange(size))
        extra.append(fan)
    faces = np.concatenate([faces] + extra)
    want = whole_test(points, faces, fillings)
    assert crossing_fillings(points, faces, fillings).tolist() == want.tolist()


def test_the_fillings_clipped_on_a_plane_are_refused_as_the_whole_test_does():
    """A fan of a flat convex loop is a triangulation seen on a coordinate plane: leaving its
    pairs with itself out (``projected``) decides as the whole test does."""
    points, faces, fillings = holed_torus(60, 20, (1, 7, 13))
    want = whole_test(points, faces, fillings)
    assert crossing_fillings(points, faces, fillings, [True] * len(fillings)).tolist() == want.tolist()
    patches = np.full(len(faces), -1)
    for k, filling in enumerate(fillings):
        patches[filling] = k
    assert np.array_equal(self_intersections(points, faces, patches=patches).pairs, self_intersections(points, faces).pairs)


@pytest.mark.parametrize("u, v, rows", [(40, 10, (0, 2, 4, 6, 8)), (60, 20, (1, 7, 13))])
@pytest.mark.parametrize("road", ["compiled", "numpy"])
def test_the_pairs_near_the_patches_leave_the_whole_test_as_it_was(u, v, rows, road, monkeypatch):
    """Told which faces may touch the patches' faces (``near_pairs``), the self-intersection
    test pairs those faces with them alone and reports every pair, contacts along lines
    included, as the whole test does (on the compiled broad phase and on numpy's)."""
    if road == "numpy":
        monkeypatch.setattr(kernels, "KERNELS", None)
    points, faces, fillings = holed_torus(u, v, rows)
    patches = np.full(len(faces), -1)
    group = np.full(len(faces), -1)
    for k, filling in enumerate(fillings):
        patches[filling] = group[filling] = k
    new = np.concatenate(fillings)
    at, face = near_pairs(points, faces, new, group)
    whole = self_intersections(points, faces, patches=patches)
    told = self_intersections(points, faces, patches=patches, nearby=np.stack([new[at], face], axis=1))
    assert whole.count > 0
    assert np.array_equal(told.pairs, whole.pairs) and told.kinds == whole.kinds
    # Told that nothing is near them, the patches' faces are paired with nothing.
    alone = self_intersections(points, faces, patches=patches, nearby=np.zeros((0, 2), dtype=np.int64))
    assert not np.isin(alone.pairs, new).any()


@pytest.mark.parametrize("seed", range(3))
def test_fillings_on_planes_in_a_soup_are_refused_as_the_whole_test_does(seed):
    """Flat convex fans (triangulations on a plane) among random triangles: their pairs with
    themselves left out, their pairs with faces not near them too."""
    rng = np.random.default_rng(seed + 10)
    points, faces = soup(seed + 10, 200)
    fillings, extra = [], []
    for _ in range(6):
        size = int(rng.choice([1, SCREENED, 40]))
        angle = np.linspace(0, 2 * np.pi, size + 2, endpoint=False)
        centre = points[:200].mean(axis=0) + (rng.random(3) - 0.5) * 8       # in and beside the soup
        rim = centre + (0.5 + rng.random() * 2) * np.stack([np.cos(angle), np.sin(angle), 0 * angle], 1)
        ids = len(points) + np.arange(size + 2)
        points = np.concatenate([points, rim])
        fillings.append(len(faces) + sum(len(e) for e in extra) + np.arange(size))
        extra.append(np.stack([np.full(size, ids[0]), ids[1:-1], ids[2:]], axis=1))
    faces = np.concatenate([faces] + extra)
    want = whole_test(points, faces, fillings)
    assert want.any() and not want.all()
    assert crossing_fillings(points, faces, fillings, [True] * len(fillings)).tolist() == want.tolist()


def numpy_walk(monkeypatch, *args):
    """``near_pairs`` on the numpy road, a few triangles walking together."""
    with monkeypatch.context() as m:
        m.setattr(near, "compiled", lambda: None)
        m.setattr(near, "WALK", 7)
        return near_pairs(*args)


@needs_kernels
@pytest.mark.parametrize("seed", range(4))
def test_the_compiled_walk_finds_the_numpy_walks_pairs(monkeypatch, seed):
    points, faces = soup(seed)
    group = np.full(len(faces), -1)
    group[:10] = 0
    query = np.arange(0, 40)
    assert kernels.KERNELS is not None
    for args in ((points, faces, query, group), (points, faces, query), holed_torus(40, 10, (0, 2, 4))[:2]
                 + (np.arange(700, 776),)):
        compiled_at, compiled_face = near_pairs(*args)
        numpy_at, numpy_face = numpy_walk(monkeypatch, *args)
        assert compiled_at.size > 0
        assert np.array_equal(compiled_at, numpy_at) and np.array_equal(compiled_face, numpy_face)


@needs_kernels
def test_the_compiled_walk_grows_its_outputs(monkeypatch):
    """One triangle meeting more boxes than the first outputs hold."""
    points, faces = soup(1, 3000)
    big = np.array([[-1e3, -1e3, -1e3], [1e3, -1e3, 1e3], [0.0, 1e3, 0.0]])
    points = np.concatenate([points, big])
    faces = np.concatenate([faces, [[len(points) - 3, len(points) - 2, len(points) - 1]]])
    query = np.array([len(faces) - 1])
    monkeypatch.setattr(near, "OUTPUTS", 4)
    at, face = near_pairs(points, faces, query)
    assert at.size > 32 * 4
    assert [a.tolist() for a in numpy_walk(monkeypatch, points, faces, query)] == [at.tolist(), face.tolist()]


def same_reports(a, b) -> bool:
    """Two output checks say the same: the topology, every self-intersecting pair with its
    kind and the samples, and the shells' nesting."""
    plain = dataclasses.replace(a, self_intersections=None, nesting=None)
    return (plain == dataclasses.replace(b, self_intersections=None, nesting=None)
            and a.self_intersections.to_dict(all_pairs=True) == b.self_intersections.to_dict(all_pairs=True)
            and a.nesting.to_dict() == b.nesting.to_dict())


def test_the_output_check_told_the_faces_near_the_fillings_reports_as_the_whole_check():
    """Fans on coordinate planes through the tube (crossing it) and in the torus's hole
    (crossing nothing): ``p3d check``'s report of the mesh is the same told which faces are near
    the fans' (``near_pairs``), as patches or not."""
    points, faces, fillings = holed_torus(40, 10, (0, 2, 4, 6, 8))
    labels = np.full(len(faces), -1)
    for k, filling in enumerate(fillings):
        labels[filling] = k
    new = np.concatenate(fillings)
    at, face = near_pairs(points, faces, new, labels)
    triangles = points[faces]
    told = checked(triangles, tuple(CHECKS), labels, np.stack([new[at], face], axis=1))
    assert told.self_intersections.count > 0
    assert not np.isin(told.self_intersections.pairs, new).all(axis=1).any()   # fans meet only the tube
    assert same_reports(told, checked(triangles, tuple(CHECKS), labels))
    assert same_reports(told, checked(triangles, tuple(CHECKS)))


def test_repair_carries_the_faces_near_the_kept_fillings_to_its_output_check(monkeypatch):
    """The holes step's pairs, renumbered past the fillings it refused (those through the
    tube, one of them before the kept ones), give the output check the report of the whole
    test."""
    points, faces, fillings = holed_torus(40, 10, (9, 3))
    triangles = points[faces[:min(f[0] for f in fillings)]]
    seen = []

    def spy(out, required, labels=None, nearby=None):
        seen.append((out, required, labels, nearby))
        return checked(out, required, labels, nearby)

    monkeypatch.setattr(pipeline, "checked", spy)
    outcome = pipeline.repair_triangles(triangles, ("degenerate", "duplicate", "orient", "holes", "outward"))
    filled = [p["filled"] for p in next(s.places for s in outcome.steps if s.name == "holes")]
    assert filled == [False, True, True, False]
    out, required, labels, nearby = seen[0]
    assert nearby is not None and len(nearby) and (labels >= 0).any()
    # The pairs are those found anew for the kept fillings in the output's numbering.
    draft, group = outcome.draft, np.full(len(out), -1)
    places = next(s.places for s in outcome.steps if s.name == "holes")
    for k, place in enumerate(p for p in places if p["filled"]):
        group[place["new_faces"]] = k
    new = np.flatnonzero(group >= 0)
    at, face = near_pairs(draft.points, draft.faces, new, group)
    assert sorted(map(tuple, nearby.tolist())) == sorted(zip(new[at].tolist(), face.tolist()))
    assert same_reports(outcome.after, checked(out, required))
