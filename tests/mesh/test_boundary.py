"""Open meshes' boundary terms (p3d_cli.mesh.boundary, boundary_terms, expansions) against
exact rational arithmetic on the meshes' own floats.

Oracles, independent of the code under test: ``exact.exact_moments`` (the world-convention
sums of T(0, a, b, c) over the faces in Python integers), ``boundary.boundary_sums`` (the net
boundary's terms in Python integers, the former exact path) and ``fractions.Fraction``; for
the open box far away, the closed form (its missing face lies in a plane through the origin,
so its world-convention moments are the closed box's).
"""

from __future__ import annotations

import json
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.kernels import SAME_BITS, bits, needs_kernels, numpy_road
from helpers.meshes import write_ascii_stl
from helpers.exact import exact_moments
import p3d_cli as p3d
from p3d_cli.io.source import array_source
from p3d_cli.mesh import boundary, boundary_sides, boundary_terms as terms_module, kernels
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.boundary import boundary_of, boundary_sums, boundary_terms, boundary_volume
from p3d_cli.mesh.boundary_sides import unbalanced_groups, unbalanced_of
from p3d_cli.mesh.closed import column_edge_keys
from p3d_cli.geometry.expansions import ExactSum, cascaded_sums, two_product, two_sum
from p3d_cli.mesh.columns import columns
from p3d_cli.geometry.rotation import rotation_from_axis_degrees

REL = 1e-9


def analysed(t):
    t = np.asarray(t)
    return analyze(array_source("t", t, str(t.dtype)), "t")


def soup(seed: int, n: int, offset, rotation=None, dtype=np.float64, size: float = 1.0) -> np.ndarray:
    """``n`` loose random triangles in a cube of side ``size`` (every side is boundary), placed."""
    t = np.random.default_rng(seed).random((n, 3, 3)) * size
    if rotation is not None:
        t = t @ rotation.T
    return (t + np.asarray(offset, dtype=np.float64)).astype(dtype)


def open_box(k: int, offset, split: bool, k2: int | None = None) -> np.ndarray:
    """The unit cube without its z = 0 face, each face a k × k2 grid (powers of two, so that
    every point is exact) of rectangles cut into two
    triangles; with ``split`` every first triangle of a square is cut into four at its
    edges' midpoints, so no side of a whole triangle meets a matching side (T-junctions
    everywhere: most sides are boundary, the surface is the same)."""
    faces = [((0, 0, 1), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 0, 1), (0, 1, 0)),
             ((1, 0, 0), (0, 1, 0), (0, 0, 1)), ((0, 0, 0), (1, 0, 0), (0, 0, 1)),
             ((0, 1, 0), (0, 0, 1), (1, 0, 0))]
    k2 = k if k2 is None else k2
    i, j = np.meshgrid(np.arange(k), np.arange(k2), indexing="ij")
    i, j = i.reshape(-1, 1) / k, j.reshape(-1, 1) / k2
    out = []
    for corner, e1, e2 in faces:
        c, e1, e2 = (np.asarray(x, dtype=np.float64) for x in (corner, e1, e2))
        p00 = c + i * e1 + j * e2
        p10, p01 = p00 + e1 / k, p00 + e2 / k2
        p11 = p10 + e2 / k2
        out.append(np.stack([p00, p11, p01], axis=1))
        if split:
            m01, m12, m20 = (p00 + p10) / 2, (p10 + p11) / 2, (p11 + p00) / 2
            out += [np.stack(x, axis=1) for x in ((p00, m01, m20), (m01, p10, m12),
                                                  (m20, m12, p11), (m01, m12, m20))]
        else:
            out.append(np.stack([p00, p10, p11], axis=1))
    return np.concatenate(out) + np.asarray(offset, dtype=np.float64)


def terms_of(t, origin=None):
    """``boundary_terms`` of ``t`` about ``origin`` (default: the bounding-box centre)."""
    t = np.asarray(t)
    flat = t.reshape(-1, 3).astype(np.float64)
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    o = 0.5 * (lo + hi) if origin is None else np.asarray(origin, dtype=np.float64)
    keys = np.sort(column_edge_keys(columns(t)))
    return boundary_terms(lambda: iter([t]), unbalanced_groups(keys), o, lo, hi), o


def oracle_terms(t, origin) -> list:
    start, end, count = boundary_of(lambda: iter([np.asarray(t)]))
    return boundary_sums(start, end, count, origin)


def assert_terms_exact_within_bounds(t, origin=None):
    found, o = terms_of(t, origin)
    exact = oracle_terms(t, o)
    assert found.sums[0] == exact[0]                       # the volume term: exact
    for got, want, bound in zip(found.sums, exact, found.error):
        assert abs(got - want) <= Fraction(float(bound))
    return found, exact


def assert_moments(moments, exact, size: float):
    """Volume and central second moments within ``REL`` of the exact world-convention values,
    the centre within ``REL`` of the part's size, and each exact error inside the stated
    uncertainty (plus the final rounding to float64)."""
    volume = float(exact.volume)
    assert abs(moments.volume - volume) <= REL * abs(volume)
    assert abs(Fraction(moments.volume) - exact.volume) <= (Fraction(moments.errors.volume)
                                                            + Fraction(float(np.spacing(abs(volume)))))
    for got, want, bound in zip(moments.center, exact.center, moments.errors.center):
        error = abs(Fraction(float(got)) - want)
        assert error <= Fraction(REL * size) + Fraction(float(np.spacing(abs(got))))
        assert error <= Fraction(float(bound)) + Fraction(float(np.spacing(abs(got))))
    central = np.array([[float(x) for x in row] for row in exact.central])
    scale = np.abs(central).max()
    for i in range(3):
        for j in range(3):
            error = abs(Fraction(float(moments.central[i, j])) - exact.central[i][j])
            assert error <= Fraction(REL * scale)
            assert error <= (Fraction(float(moments.errors.central[i, j]))
                             + Fraction(float(np.spacing(scale))))


ROTATION = rotation_from_axis_degrees(np.array([1.0, 2.0, 3.0]), 37.0)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8, -3e7])
@pytest.mark.parametrize("rotated", [False, True])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_soup_terms_are_exact_in_volume_and_within_their_bounds(offset, rotated, dtype):
    size = 1024.0 if dtype == np.float32 and abs(offset) >= 1e7 else 1.0
    t = soup(3, 60, [offset, -0.5 * offset, 0.25], ROTATION if rotated else None, dtype, size)
    assert_terms_exact_within_bounds(t)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8])
@pytest.mark.parametrize("rotated", [False, True])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_far_soups_moments_match_the_exact_world_convention(offset, rotated, dtype):
    # float32 resolves 8 at 1e8: the part is made big enough to keep its shape there.
    size = 1024.0 if dtype == np.float32 and offset >= 1e8 else 1.0
    t = soup(11, 400, [offset, offset, 0.0], ROTATION if rotated else None, dtype, size)
    found = analysed(t)
    assert found.closed is False and found.bounding is False and found.boundary_edges == 3 * len(t)
    assert_moments(found.moments, exact_moments(t), 2.0 * size)


@pytest.mark.parametrize("offset", [0.0, 1e4, 1e8])
@pytest.mark.parametrize("split", [False, True])
def test_open_box_far_away_has_the_closed_box_moments(offset, split):
    # The missing face is in the plane z = 0, through the origin: its cone is flat, so the
    # world-convention moments are exactly the unit cube's, however far along x and y.
    t = open_box(8, [offset, offset, 0.0], split)
    found = analysed(t)
    assert found.bounding is False
    exact = exact_moments(t)
    assert exact.volume == 1 and exact.central[0][0] == Fraction(1, 12)
    assert_moments(found.moments, exact, 1.0)
    assert_terms_exact_within_bounds(t)


@pytest.mark.parametrize("offset", [1e4, 1e8])
def test_rotated_open_box_far_away(offset):
    t = open_box(8, [0.0, 0.0, 0.0], True, 4) @ ROTATION.T + [offset, 2 * offset, -offset]
    assert_moments(analysed(t).moments, exact_moments(t), 1.7)
    assert_terms_exact_within_bounds(t)


def test_open_mesh_with_a_few_holes_uses_the_membership_path():
    t = open_box(10, [1e8, -1e8, 5.0], False)
    unbalanced = unbalanced_of(lambda: iter([t]))
    assert not unbalanced.most and unbalanced.edges == 40      # the missing face's rim
    assert_moments(analysed(t).moments, exact_moments(t), 1.0)
    assert_terms_exact_within_bounds(t)


def test_soup_and_membership_paths_give_the_same_terms():
    t = open_box(4, [1e8, 3.0, -2e7], True, 8)
    keys = np.sort(column_edge_keys(columns(t)))
    groups = unbalanced_groups(keys)
    lo, hi = t.reshape(-1, 3).min(axis=0), t.reshape(-1, 3).max(axis=0)
    o = 0.5 * (lo + hi)
    every = boundary_terms(lambda: iter([t]), groups, o, lo, hi)
    some = boundary_terms(lambda: iter([t]), boundary_sides.Unbalanced(groups.ids, groups.edges, 1, 10**9), o, lo, hi)
    exact = oracle_terms(t, o)
    assert every.sums[0] == some.sums[0] == exact[0]
    for a, b, want, ea, eb in zip(every.sums, some.sums, exact, every.error, some.error):
        assert abs(a - want) <= Fraction(float(ea)) and abs(b - want) <= Fraction(float(eb))


@needs_kernels
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize("holes", [1, 3, 40])
def test_compiled_sides_are_the_numpy_ones_bit_for_bit(monkeypatch, dtype, holes):
    """``unbalanced_sides`` with the compiled ``pick_sides`` and with the numpy code: the same
    sides, in the same order and chunks, the same bits (a rim of a few ids, tested by equality
    in numpy, and one of more, by the table and a binary search; -0.0 read as 0.0; a side whose
    ends are one point left out; several blocks)."""
    t = open_box(12, [-0.0, 1e8, 3.0], True, 9).astype(dtype)
    t = np.delete(t, np.arange(0, len(t), max(1, len(t) // holes))[:holes], axis=0)
    t[5, 1] = t[5, 0]                                        # a side from a point to itself
    t[:, :, 0][t[:, :, 0] == 0] = -0.0
    blocks = [t[:100], t[100:101], t[101:]]
    ids = unbalanced_of(lambda: iter(blocks)).ids
    assert ids.size > (16 if holes > 1 else 0)
    compiled = list(boundary_sides.unbalanced_sides(iter(blocks), ids))
    monkeypatch.setattr(kernels, "KERNELS", None)
    numpy_sides = list(boundary_sides.unbalanced_sides(iter(blocks), ids))
    assert len(compiled) == len(numpy_sides)
    for (u, v), (u2, v2) in zip(compiled, numpy_sides):
        assert u.flags.c_contiguous and v.flags.c_contiguous
        assert np.array_equal(bits(u), bits(u2)) and np.array_equal(bits(v), bits(v2))


def test_check_volume_term_is_the_same_exact_number():
    t = soup(5, 200, [1e8, 1e8, 0.5], ROTATION)
    found, o = terms_of(t)
    six_volume, lost = boundary_volume(iter([t]), unbalanced_of(lambda: iter([t])), o)
    assert six_volume == found.sums[0] and lost == 0.0


def test_inexact_local_coordinates_fall_back_to_exact_integers(monkeypatch):
    t = soup(7, 50, [0.3, 1e8, 0.0])
    # A frame in which u - o' is not exact: the fast path must notice and not use it.
    monkeypatch.setattr(boundary, "frame_origin", lambda lo, hi: np.array([0.1, 1e8 / 3, 0.7]))
    found, o = terms_of(t)
    assert found.sums == oracle_terms(t, o)


def test_huge_world_coordinates_keep_the_volume_term_exact():
    t = soup(2, 20, [2.0 ** 500, 0.0, 0.0]) * np.array([1.0, 2.0 ** 480, 1.0])
    six_volume, _ = boundary_volume(iter([t]), unbalanced_of(lambda: iter([t])), np.zeros(3) + 1.5)
    assert six_volume == oracle_terms(t, np.zeros(3) + 1.5)[0]


def test_large_far_soup_end_to_end(tmp_path):
    # More than 65,536 boundary edges (the former limit of the exact terms), far away.
    t = open_box(64, [1e8, 1e8, 0.0], True, 32)
    path = tmp_path / "soup.stl"
    write_ascii_stl(path, t)
    result = p3d.props(str(path))
    assert result.facts.closed is False
    p = result.properties
    assert abs(p.volume - 1.0) <= REL
    assert np.abs(p.center_of_mass - [1e8 + 0.5, 1e8 + 0.5, 0.5]).max() <= REL + np.spacing(1e8)
    assert np.abs(p.inertia - np.eye(3) / 6).max() <= REL / 6
    inertia_bound = np.asarray(result.uncertainty["inertia"])
    assert (np.abs(p.inertia - np.eye(3) / 6) <= inertia_bound + 1e-15).all()
    assert (inertia_bound < 1e-10).all()
    report = p3d.check(str(path))
    assert report.report.boundary_edges > 65536
    assert report.report.volume == p.volume
    assert json.dumps(report.report.volume) == json.dumps(p.volume)


@pytest.mark.parametrize("compiled", [False, pytest.param(True, marks=needs_kernels)])
def test_exact_sum_against_fractions(compiled):
    """``ExactSum`` with numpy's binning and with the compiled one (``exact_bins``): the exact
    sums, and the same float bins bit for bit (each bin's sum is exact in any order)."""
    rng = np.random.default_rng(0)
    x = rng.standard_normal((4, 500)) * np.exp2(rng.integers(-80, 80, (4, 500)))
    x[0, :6] = [1e-310, -3e-320, 5e307, -5e307, 0.0, -0.0]
    x[3, :3] = [np.finfo(np.float64).max, -np.finfo(np.float64).max, 5e-324]
    total = ExactSum(2, kernels.KERNELS.exact_bins if compiled else None)
    total.add(x, np.array([0, 1, 0, 1]))
    total.add(x[:1], np.array([1]))
    if compiled:
        plain = ExactSum(2)
        plain.add(x, np.array([0, 1, 0, 1]))
        plain.add(x[:1], np.array([1]))
        assert np.array_equal(bits(total._pending_high), bits(plain._pending_high))
        assert np.array_equal(bits(total._pending_low), bits(plain._pending_low))
    want = [sum(map(Fraction, x[0].tolist() + x[2].tolist())),
            sum(map(Fraction, x[1].tolist() + x[3].tolist() + x[0].tolist()))]
    assert total.totals() == want


@needs_kernels
def test_exact_bins_refuses_arrays_that_do_not_fit():
    high, low = np.zeros(2 * 2098), np.zeros(2 * 2098)
    with pytest.raises(ValueError, match="exact_bins"):
        kernels.KERNELS.exact_bins(np.ones((2, 3)), np.array([2 * 2098 + 1073], dtype=np.int64), high, low)
    with pytest.raises(ValueError, match="exact_bins"):
        kernels.KERNELS.exact_bins(np.ones((2, 3)), np.array([1073, 2098 + 1073], dtype=np.int64), high, low[:5])
    with pytest.raises(TypeError, match="exact_bins"):
        kernels.KERNELS.exact_bins(np.ones((2, 3), dtype=np.float32), np.array([1073, 3171]), high, low)
    assert not high.any() and not low.any()


def test_cascaded_sums_are_within_their_bound():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((3, 1001)) * np.exp2(rng.integers(-30, 30, (3, 1001)))
    high, low, factor = cascaded_sums(x)
    for row in range(3):
        exact = sum(map(Fraction, x[row].tolist()))
        bound = Fraction(factor) * Fraction(2) ** -106 * sum(abs(Fraction(v)) for v in x[row].tolist())
        assert abs(Fraction(float(high[row])) + Fraction(float(low[row])) - exact) <= bound


@given(st.lists(st.floats(-1e150, 1e150, allow_nan=False), min_size=2, max_size=40),
       st.lists(st.floats(-1e150, 1e150, allow_nan=False), min_size=2, max_size=40))
def test_two_product_and_two_sum_are_error_free(a, b):
    n = min(len(a), len(b))
    x, y = np.array(a[:n]), np.array(b[:n])
    p, e = two_product(x, y)
    s, f = two_sum(x, y)
    for xi, yi, pi, ei, si, fi in zip(x.tolist(), y.tolist(), p.tolist(), e.tolist(), s.tolist(), f.tolist()):
        product = Fraction(xi) * Fraction(yi)
        if product == 0 or abs(product) > 2.0 ** -900:     # no underflow of the error term
            assert Fraction(pi) + Fraction(ei) == product
        assert Fraction(si) + Fraction(fi) == Fraction(xi) + Fraction(yi)


@given(st.integers(0, 2**32 - 1), st.integers(3, 40), st.sampled_from([0.0, 1.0, 1e3, 1e6, 1e8, 1e12]),
       st.floats(0.0, 360.0), st.booleans())
def test_random_soups_terms_property(seed, n, offset, degrees, float32):
    rotation = rotation_from_axis_degrees(np.array([0.3, -1.0, 0.5]), degrees)
    t = soup(seed, n, [offset, -offset, 0.5 * offset], rotation, np.float32 if float32 else np.float64)
    found, exact = assert_terms_exact_within_bounds(t)
    # The bound is small: far below the terms' own size (|o|³ L² for the second moments).
    scale = max(1.0, offset) ** 3
    assert (found.error[4:] <= 1e-20 * scale * n).all()


def test_frame_origin_makes_local_coordinates_exact():
    lo = np.array([1e8, -3.0, 0.1])
    hi = np.array([1e8 + 1.0, -1.0, 1.0])
    frame = terms_module.frame_origin(lo, hi)
    u = np.random.default_rng(4).uniform(lo, hi, size=(1000, 3))
    a, error = two_sum(u, -frame)
    assert not error.any()
    assert frame[2] == 0.0 and lo[0] <= frame[0] <= hi[0] and lo[1] <= frame[1] <= hi[1]


def test_coordinates_spanning_beyond_the_scaling_fall_back_to_exact_integers():
    # Scaled by 2**-333 to |a| <= 1, a coordinate of 5e-324 (the least subnormal) would vanish.
    t = soup(8, 6, [0.0, 0.0, 0.0])
    t[0, 0] = [5e-324, 3e-320, 0.0]
    t[1, 1] = [1e100, 0.5, 0.25]
    found, o = terms_of(t)
    assert found.sums == oracle_terms(t, o)


def _local_sides(rng, n: int, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Scaled local end points ``(3, n)`` in [-1, 1] of a few kinds: uniform; on a grid of
    2**-20 with sides sharing ends (cancelling products); spread over 600 binary orders, with
    ±0.0 and products that underflow."""
    if kind == "uniform":
        return rng.uniform(-1, 1, (3, n)), rng.uniform(-1, 1, (3, n))
    if kind == "grid":
        a = np.ldexp(rng.integers(-2 ** 20, 2 ** 20, (3, n)).astype(np.float64), -20)
        b = a[:, ::-1].copy()
        b[:, :n // 2] = rng.uniform(-1, 1, (3, n // 2))
        return a, b
    a = rng.uniform(-1, 1, (3, n)) * np.ldexp(1.0, -rng.integers(0, 600, (3, n)))
    b = rng.uniform(-1, 1, (3, n)) * np.ldexp(1.0, -rng.integers(0, 600, (3, n)))
    a[0, ::7], b[1, ::5] = -0.0, 0.0
    return a, b


@needs_kernels
@pytest.mark.parametrize("kind", ["uniform", "grid", "spread"])
@pytest.mark.parametrize("n", [1, 2, 3, 7, 8, 9, 127, 128, 129, 255, 257, 1000, 1025, 4097, 16384, 20001])
def test_compiled_local_terms_are_the_numpy_ones_bit_for_bit(n, kind):
    """The compiled ``local_terms`` replays ``Locals``' numpy code: every product, error-free
    sum, cascade level and numpy row sum, so the same bits (rows of one to 20,001 sides: the
    pairwise sums' leaves and halves, odd cascade levels, underflow, signed zeros)."""
    a, b = _local_sides(np.random.default_rng(n), n, kind)
    # World coordinates near a frame far off (u - frame exact by Sterbenz's lemma, scaled by
    # 2**-7 into [-1, 1]); the spread's tiny ones as they are, about the origin.
    frame, scale = (np.zeros(3), 0) if kind == "spread" else (np.array([3.0 * 2 ** 30, -5.0 * 2 ** 10, 0.0]), 7)
    u, v = np.ldexp(a, scale) + frame[:, None], np.ldexp(b, scale) + frame[:, None]
    a, b = terms_module.local_coordinates(u, frame, scale), terms_module.local_coordinates(v, frame, scale)
    fast = terms_module._compiled_terms(kernels.KERNELS, u, v, frame, scale)
    slow = terms_module.local_terms(a, b)
    assert fast.underflow == slow.underflow
    if kind == "spread" and n >= 100:
        assert slow.underflow > 0
    for name in ("parts", "q_high", "r_sum", "mag", "big_t", "big_w", "low_sums"):
        x, y = getattr(fast, name), getattr(slow, name)
        assert x.shape == y.shape, name
        if name == "low_sums" and not SAME_BITS:
            # Before numpy 2.3 numpy cuts long row sums elsewhere: the low parts' sums (about
            # 2**-53 of the high parts) then agree far inside their rounding bound.
            scale = max(np.abs(fast.q_high).max(), np.abs(fast.r_sum).max(), 1e-300)
            np.testing.assert_allclose(x, y, rtol=1e-9, atol=1e-25 * scale)
        else:
            assert np.array_equal(bits(x), bits(y)), name


@needs_kernels
def test_locals_totals_are_the_same_with_and_without_the_kernel():
    """Whole ``Locals`` runs over batches of several sizes: the same exact sums and bound."""
    rng = np.random.default_rng(3)
    batches = [_local_sides(rng, n, kind) for n, kind in [(500, "uniform"), (1, "grid"), (3000, "spread"),
                                                         (9000, "uniform")]]

    def run():
        local = terms_module.Locals()
        for a, b in batches:
            local.add(a, b, np.zeros(3), 0)
        return local.cross_totals(), local.totals(), local.underflow

    (p, p_error), (qr, qr_error), underflow = run()
    (p2, p2_error), (qr2, qr2_error), underflow2 = numpy_road(run)
    assert p == p2 and p_error == p2_error and underflow == underflow2
    if SAME_BITS:
        assert qr == qr2 and np.array_equal(bits(qr_error), bits(qr2_error))
    else:
        np.testing.assert_allclose(qr_error, qr2_error, rtol=1e-12)
        assert all(abs(float(x - y)) <= e for x, y, e in zip(qr, qr2, qr_error))


@pytest.mark.parametrize("compiled", [False, pytest.param(True, marks=needs_kernels)])
def test_locals_refuse_inexact_local_coordinates(compiled):
    """``Locals.add`` in world coordinates: a side whose ``u - frame`` is not an exact float,
    or whose scaling loses bits, raises ``InexactLocal``, with and without the kernel."""
    u = np.array([[0.1, 0.5], [0.25, 0.75], [0.0, 1.0]])
    v = u[:, ::-1].copy()
    local = terms_module.Locals()
    add = local.add if compiled else (lambda *args: numpy_road(local.add, *args))
    add(u, v, np.zeros(3), 1)                                   # exact: halves
    for frame, scale in [(np.array([1e8 / 3, 0.0, 0.0]), 0),   # 0.1 - 1e8/3 is not
                         (np.zeros(3), 1074)]:                  # 0.1 · 2**-1074 underflows
        with pytest.raises(terms_module.InexactLocal):
            add(u, v, frame, scale)


@needs_kernels
def test_local_terms_refuses_arrays_that_do_not_fit():
    """The kernel checks its arrays' sizes against the sides' count before writing any."""
    u = np.ones((3, 4))
    out = [np.zeros((12, 4)), np.zeros((9, 4)), np.zeros((3, 4)), np.zeros((3, 4)), np.zeros((6, 4)),
           np.zeros(27), np.zeros(18)]
    assert kernels.KERNELS.local_terms(u, u, (0.0, 0.0, 0.0), 0, *out) == 0
    for bad in (1, 5, 6):
        wrong = list(out)
        wrong[bad] = np.zeros(wrong[bad].size + 1)
        with pytest.raises(ValueError, match="local_terms"):
            kernels.KERNELS.local_terms(u, u, (0.0, 0.0, 0.0), 0, *wrong)
    with pytest.raises(ValueError, match="local_terms"):
        kernels.KERNELS.local_terms(u, np.ones((3, 5)), (0.0, 0.0, 0.0), 0, *out)
