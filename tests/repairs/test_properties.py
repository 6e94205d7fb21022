"""Properties of every repair, on closed meshes broken at random: it never fails, an output it
calls fixed passes ``p3d check``, and every face it did not touch is the input's, bit for bit."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

import p3d_cli as p3d
from helpers.tori import grid_torus
from p3d_cli.repairs import repair


BASE = grid_torus(6, 5)           # 60 faces


@st.composite
def broken(draw):
    """The torus with some faces removed, some turned round, some repeated, a few degenerate
    faces added; float32 or float64, anywhere."""
    n = len(BASE)
    removed = draw(st.sets(st.integers(0, n - 1), max_size=6))
    turned = draw(st.sets(st.integers(0, n - 1), max_size=12))
    repeated = draw(st.lists(st.integers(0, n - 1), max_size=3))
    degenerate = draw(st.integers(0, 2))
    whole = draw(st.booleans())
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    shift = draw(st.sampled_from([0.0, 1e3, -2.5e6]))
    triangles = BASE.copy()
    triangles[sorted(turned)] = triangles[sorted(turned)][:, [0, 2, 1]]
    if whole:
        triangles = triangles[:, [0, 2, 1]]
    keep = [f for f in range(n) if f not in removed]
    parts = [triangles[keep], triangles[repeated][:, ::-1]]
    for k in range(degenerate):
        a, b = triangles[k, 0], triangles[k, 1]
        parts.append(np.array([[a, b, a]]))
    return (np.concatenate(parts) + shift).astype(dtype)


@given(broken())
def test_repairs_never_fail_and_keep_their_word(triangles):
    mesh, report = repair(triangles)
    out = mesh.triangles
    assert out.dtype == triangles.dtype
    if report.fixed:
        assert p3d.check(mesh.source).ok
    else:
        assert report.unfixed
    removed = {f for name in ("degenerate", "duplicate") for f in report.step(name).faces}
    added = report.step("holes").new_faces
    assert len(out) == len(triangles) - len(removed) + len(added)
    kept = [f for f in range(len(triangles)) if f not in removed]
    flipped = set(report.step("orient").faces) ^ set(report.step("outward").faces)
    split = set(report.step("holes").faces)
    for row, f in enumerate(kept):           # untouched, or the same corners turned round
        if f in split:
            continue
        expected = triangles[f][[0, 2, 1]] if f in flipped else triangles[f]
        assert out[row].tobytes() == expected.tobytes()
    assert list(added) == list(range(len(kept), len(out)))
