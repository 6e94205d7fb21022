"""The closed test on bucketed keys (issue 32): each bucket sorted and checked where it lies
(``kernels.Buckets.pair_up``, the compiled ``paired``) gives the verdict of ``keys_pair_up``
over all the keys, on every input; a mesh it finds closed never moves its keys together; one
it does not goes on to the open road with the same keys. Checked against the sorted keys,
against the numpy code (no kernels) and against the exact-vertex test (``closed_exact``)."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.io.source import array_source
from p3d_cli.mesh import kernels
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.closed import closed_exact, keys_pair_up
from test_kernels import assert_same_analysis
from test_paired import torus

KERNELS = kernels.KERNELS
if KERNELS is None and os.environ.get("CI") != "true":
    pytestmark = pytest.mark.skip(reason="the compiled kernels are not built here")

#: A torus of 2 · 120 · 100 = 24,000 faces: 72,000 sides, past the 65,536 from which the
#: compiled pass deals the keys to buckets.
BIG = torus(120, 100, shift=(2.5, -1.25, 0.75)).astype(np.float32)

MASK = np.uint64(2**64 - 1)


def dealt(keys: np.ndarray) -> kernels.Buckets:
    buckets = kernels.Buckets(max(keys.size, 1))
    buckets.add(keys)
    assert not buckets.overflow
    return buckets


@st.composite
def key_sets(draw):
    """Side keys of edges used 0-3 times each way, some edges at the ends of the key range
    and at bucket boundaries (2e and 2e + 1 always share a bucket: they differ in bit 0)."""
    count = draw(st.integers(0, 400))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    edges = rng.integers(0, 2**63, count, dtype=np.uint64)
    special = np.array([0, 2**63 - 1, 2**62 - 1, 2**62, 2**61 - 1], dtype=np.uint64)
    edges = np.unique(np.concatenate([edges, special[:draw(st.integers(0, special.size))]]))
    uses = draw(st.sampled_from(["closed", "one off", "any"]))
    forward = np.ones(edges.size, dtype=np.int64)
    backward = np.ones(edges.size, dtype=np.int64)
    if uses == "one off" and edges.size:
        i = draw(st.integers(0, edges.size - 1))
        forward[i], backward[i] = draw(st.sampled_from([(0, 1), (1, 0), (2, 1), (1, 2), (2, 2), (2, 0), (3, 3),
                                                        (0, 0)]))
    elif uses == "any":
        forward = rng.integers(0, 4, edges.size)
        backward = rng.integers(0, 4, edges.size)
    keys = np.concatenate([np.repeat(edges << np.uint64(1), backward),
                           np.repeat((edges << np.uint64(1)) | np.uint64(1), forward)]).astype(np.uint64)
    rng.shuffle(keys)
    return keys


@given(key_sets())
def test_paired_is_keys_pair_up(keys):
    buckets = dealt(keys)
    expected = keys_pair_up(keys.copy())
    assert buckets.pair_up() is expected
    # Whatever it found, the buckets still hold the keys: the open road sorts them together.
    assert np.array_equal(buckets.sorted_keys(), np.sort(keys))


def test_paired_on_many_keys():
    """Enough keys for many buckets (each sorted by the radix passes, not insertion alone)."""
    rng = np.random.default_rng(5)
    edges = np.unique(rng.integers(0, 2**63, 600_000, dtype=np.uint64))
    pairs = np.concatenate([edges << np.uint64(1), (edges << np.uint64(1)) | np.uint64(1)])
    rng.shuffle(pairs)
    assert dealt(pairs).pair_up() is True
    for extra in (pairs[:1], pairs[:2], pairs[[0, 1]] ^ np.uint64(1)):
        keys = np.concatenate([pairs, extra])
        assert dealt(keys).pair_up() is keys_pair_up(keys.copy()) is False
    assert dealt(pairs[1:]).pair_up() is False
    assert dealt(pairs[:0]).pair_up() is False              # no sides: nothing closed


def variants():
    rng = np.random.default_rng(7)
    t = BIG
    flipped = t[:, ::-1]
    yield "closed", t
    yield "faces shuffled (the open front is the whole mesh)", t[rng.permutation(len(t))]
    yield "corners rotated", np.roll(t, 1, axis=1)
    yield "one face flipped", np.concatenate([t[:5], flipped[5:6], t[6:]])
    yield "one face removed", t[1:]
    yield "a face twice (its edges used three times)", np.concatenate([t, t[10:11]])
    yield "a face and its flip added (edges used twice each way)", np.concatenate([t, t[10:11], flipped[10:11]])
    yield "the mesh twice (every edge twice each way)", np.concatenate([t, t])
    yield "the mesh and its flip", np.concatenate([t, flipped])
    yield "the mesh twice, shuffled", np.concatenate([t, t])[rng.permutation(2 * len(t))]
    yield "every face flipped", flipped
    yield "a sliver side (two corners alike)", np.concatenate([t, np.stack([t[0, 0], t[0, 0], t[0, 1]])[None]])


@pytest.mark.parametrize("name,triangles", list(variants()), ids=[name for name, _ in variants()])
def test_adversarial_meshes_same_verdicts(name, triangles):
    """With the kernels (bucketed keys, checked in place) and without (numpy's sort): the same
    verdicts, bounds and sums; and the verdict is the exact-vertex test's."""
    source = array_source("stl-binary", np.ascontiguousarray(triangles), "float32")
    assert 3 * source.face_count >= 1 << 16                 # the bucketed road
    assert_same_analysis(source)
    assert analyze(source, "x").closed is closed_exact(triangles)


def test_a_closed_mesh_never_moves_its_keys(monkeypatch):
    """The point of checking in place: a closed mesh's keys are never sorted together (that
    move touched every key's page a second time); an open one's still are, for its road."""
    calls = []
    original = kernels.Buckets.sorted_keys

    def counted(self):
        calls.append(1)
        return original(self)

    monkeypatch.setattr(kernels.Buckets, "sorted_keys", counted)
    closed = analyze(array_source("stl-binary", BIG, "float32"), "x")
    assert closed.closed is True and closed.bounding is True and calls == []
    opened = analyze(array_source("stl-binary", BIG[1:], "float32"), "x")
    assert opened.closed is False and opened.bounding is False and calls == [1]
