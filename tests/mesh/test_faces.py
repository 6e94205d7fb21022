"""Zero area decided exactly: the filtered predicate against fractions.Fraction."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.kernels import needs_kernels
from helpers.meshes import write_ascii_stl
from p3d_cli.mesh.kernels import KERNELS
from p3d_cli.io import load_mesh
from p3d_cli.mesh.faces import zero_area_faces
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.topology import topology
from p3d_cli.mesh.verdicts import check_source
from test_topology_oracle import exact_zero_area

#: Three nearly collinear float64 points whose float64 cross product rounds to exactly
#: (0, 0, 0), while the exact one is about (2.9e-16, 0, -5.5e-17): not degenerate.
SLIVER = [[0.2997118905373848, 0.42268722119765845, 0.028319671145462966],
          [0.42399516703694873, 1.0933116358912889, 0.675509182719713],
          [0.6725617200360766, 2.4345604652785493, 1.9698882058682132]]


def test_sliver_whose_float_cross_product_vanishes_is_not_degenerate():
    t = np.array([SLIVER])
    assert not np.cross(t[0, 1] - t[0, 0], t[0, 2] - t[0, 0]).any()   # the old test said zero
    assert not exact_zero_area(t[0])
    r = topology(t)
    assert r.zero_area_faces == 0 and r.degenerate_faces == 0


def test_sliver_in_a_file_is_judged_on_the_files_own_floats(tmp_path):
    collinear = [[0.0, 0.0, 0.0], [0.5, 0.25, 0.125], [1.0, 0.5, 0.25]]   # exactly collinear
    path = tmp_path / "slivers.stl"
    write_ascii_stl(path, np.array([SLIVER, collinear]))
    mesh = load_mesh(str(path))
    floats = mesh.triangles()
    expected = [f for f in range(len(floats)) if exact_zero_area(floats[f])]
    assert expected == [1]
    r = check_source(mesh, str(path)).report
    assert r.zero_area_faces == 1 and r.degenerate_face_samples == (1,)


def nearly_collinear(seed: int, n: int, dtype) -> np.ndarray:
    rng = np.random.default_rng(seed)
    a = rng.uniform(-2, 2, (n, 3))
    d = rng.uniform(-1, 1, (n, 3))
    s = rng.integers(-3, 4, (n, 1)).astype(float)
    t = np.stack([a, a + d, a + s * d], axis=1)
    # Some exactly representable collinear faces, some repeated corners, some tiny offsets.
    t[::5, 2] = t[::5, 0]
    t[1::5] = np.round(t[1::5] * 8) / 8
    t[1::5, 2] = 2 * t[1::5, 1] - t[1::5, 0]
    t[2::5, 2] += rng.choice([0.0, 1e-17, 1e-300, 1e300], size=(len(t[2::5]), 1))
    with np.errstate(over="ignore"):
        return t.astype(dtype)


@given(st.integers(0, 2**32 - 1), st.integers(1, 60), st.sampled_from([np.float32, np.float64]))
def test_zero_area_matches_exact_rational_arithmetic(seed, n, dtype):
    t = nearly_collinear(seed, n, dtype)
    t = t[np.isfinite(t).all(axis=(1, 2))]
    expected = [f for f in range(len(t)) if exact_zero_area(t[f])]
    assert zero_area_faces(columns(t)).tolist() == expected


def test_huge_and_tiny_coordinates_are_decided_exactly():
    t = np.array([[[0, 0, 0], [1e-300, 0, 0], [0, 1e-300, 0]],       # products underflow
                  [[0, 0, 0], [1e300, 1e300, 0], [-1e300, -1e300, 0]],  # products overflow
                  [[0, 0, 0], [1e300, 1e300, 0], [-1e300, 1e300, 0]]])
    assert zero_area_faces(columns(t)).tolist() == [1]


def _planted_faces(rng: np.random.Generator) -> np.ndarray:
    """Faces the orientation filter cannot decide, of every kind: repeated corners (by value),
    exactly collinear corners (dyadic and not), one-ulp slivers, signed zeros, subnormal and
    huge coordinates (past the vectorised test's 2**±400, left to rationals)."""
    out = []
    for _ in range(200):
        p, q = rng.normal(size=3), rng.normal(size=3)
        out.append([p, p, q])                                         # a repeated corner
        out.append([p, q, q.copy()])
        t = rng.integers(-8, 8, size=3).astype(float)
        out.append([t, 2 * t, 3 * t])                                 # collinear, exactly
        out.append([p, p + (q - p) * 0.5, q])                         # collinear up to rounding
        r = p + (q - p) * 0.25
        out.append([p, np.nextafter(r, r + 1), q])                    # one ulp off the line
        out.append([p * 1e-310, q * 1e-310, (p + q) * 1e-310])        # subnormal
        out.append([p * 1e150, q * 1e150, (p + q) * 1e150])            # products past 2**996
        out.append([[0.0, 1.0, 2.0], [-0.0, 2.0, 4.0], [0.0, 3.0, 6.0]])
    return np.array(out, dtype=np.float64)


def test_the_vectorised_exact_test_gives_the_rational_answers_on_planted_faces():
    from p3d_cli.mesh.faces import _exact_zero_area, exactly_zero_area

    triangles = _planted_faces(np.random.default_rng(3))
    cols = columns(triangles)
    want = np.array([_exact_zero_area(cols[:, :, f]) for f in range(len(triangles))])
    zero, undecided = exactly_zero_area(cols)
    decided = ~undecided
    assert np.array_equal(zero[decided], want[decided])
    assert undecided.sum() <= 400                                     # only the 2**±400 faces
    assert np.array_equal(zero_area_faces(cols), np.flatnonzero(want))
    assert want.sum() > 600 and (~want).sum() > 200                    # both kinds were planted


def numpy_undecided(block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The zero-area faces of ``block`` by the numpy code, and the faces its filter left to the
    exact tests (none when it certified every face)."""
    from p3d_cli.mesh import faces

    seen = [np.zeros(0, dtype=np.int64)]
    real = faces._decided

    def spy(cols, undecided):
        seen[0] = undecided
        return real(cols, undecided)

    faces._decided = spy
    try:
        got = zero_area_faces(columns(block))
    finally:
        faces._decided = real
    return got, seen[0]


@needs_kernels
@given(st.integers(0, 2**32 - 1), st.integers(1, 400), st.sampled_from([np.float32, np.float64]))
def test_the_compiled_filter_leaves_the_faces_numpys_leaves(seed, n, dtype):
    from p3d_cli.mesh.faces import zero_area_faces_compiled

    rng = np.random.default_rng(seed)
    t = np.concatenate([nearly_collinear(seed, n, np.float64), _planted_faces(rng)[:n]])
    t = t[rng.permutation(len(t))]
    with np.errstate(over="ignore"):
        t = t.astype(dtype)
    t = t[np.isfinite(t).all(axis=(1, 2))]         # callers refuse the others first
    block = t
    if dtype == np.float32:     # as a binary STL holds them: 50-byte records, read in place
        records = np.zeros((len(t), 50), dtype=np.uint8)
        records[:, 12:48] = t.reshape(len(t), 9).view(np.uint8)
        block = records[:, 12:48].view(np.float32).reshape(len(t), 3, 3)
        assert block.strides[0] == 50 and np.array_equal(block, t, equal_nan=True)
    expected, left = numpy_undecided(t)
    undecided = np.empty(len(t), dtype=np.int64)
    count = KERNELS.area_filter(block, undecided)
    assert np.array_equal(undecided[:count], left)
    got = zero_area_faces_compiled(block, KERNELS)
    assert got.dtype == np.int64 and np.array_equal(got, expected)


@needs_kernels
def test_the_compiled_filter_on_huge_tiny_and_nonfinite_faces():
    from p3d_cli.mesh.faces import zero_area_faces_compiled

    t = np.array([[[0, 0, 0], [1e-300, 0, 0], [0, 1e-300, 0]],
                  [[0, 0, 0], [1e300, 1e300, 0], [-1e300, -1e300, 0]],
                  [[0, 0, 0], [1e300, 1e300, 0], [-1e300, 1e300, 0]],
                  [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
                  [[0, 0, 0], [0, 0, 0], [0, 0, 0]]])
    assert zero_area_faces_compiled(t, KERNELS).tolist() == [1, 4]
    undecided = np.empty(2, dtype=np.int64)
    nan = np.array([[[0, 0, 0], [np.nan, 1, 0], [0, 1, 0]]])
    assert KERNELS.area_filter(nan, undecided) == 1             # a NaN certifies nothing
    with pytest.raises(ValueError):
        KERNELS.area_filter(t, undecided)                       # room for 2 of 5 faces
