"""``p3d props``' closed test on half the keys (issue 32, ``kernels.ForwardBuckets``): the
forward keys dealt to buckets, each bucket checked for a key twice where it lies (compiled
``distinct``), and the balance of the two directions, give the verdict of ``keys_pair_up`` over
all the keys on every input; a mesh found closed never sorts its keys together; one not found
closed goes on to the open road with every key. Checked against the sorted keys, against the
numpy code (no kernels) and against the exact-vertex test (``closed_exact``)."""

from __future__ import annotations


import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from helpers.kernels import needs_kernels
from p3d_cli.io.source import array_source
from p3d_cli.mesh import kernels
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.closed import closed_exact, column_edge_keys, keys_pair_up
from p3d_cli.mesh.columns import columns
from test_kernels import assert_same_analysis
from test_paired import torus

KERNELS = kernels.KERNELS
pytestmark = needs_kernels

#: A torus of 2 · 120 · 100 = 24,000 faces: 72,000 sides, past the 65,536 from which the
#: compiled pass deals the keys to buckets.
BIG = torus(120, 100, shift=(2.5, -1.25, 0.75)).astype(np.float32)

MASK = np.uint64(2**64 - 1)


def dealt(keys: np.ndarray) -> kernels.ForwardBuckets:
    """The keys through the numpy road of ``ForwardBuckets``."""
    buckets = kernels.ForwardBuckets(max(keys.size, 1))
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
def test_forward_keys_and_balance_are_keys_pair_up(keys):
    buckets = dealt(keys)
    assert buckets.closed() is keys_pair_up(keys.copy())
    forward = keys[(keys & np.uint64(1)) == 1]
    assert buckets.backward == keys.size - forward.size
    assert np.array_equal(buckets.sorted_keys(), np.sort(forward))


def test_balance_sees_two_edges_each_used_one_way():
    """Counts equal, no forward key twice: only the balance tells edge a (forward only) and
    edge b (backward only) from one edge used once each way."""
    a, b = np.uint64(12345), np.uint64(67890)
    one_way = np.array([(a << np.uint64(1)) | np.uint64(1), b << np.uint64(1)], dtype=np.uint64)
    assert dealt(one_way).closed() is keys_pair_up(one_way.copy()) is False
    both = np.array([(a << np.uint64(1)) | np.uint64(1), a << np.uint64(1)], dtype=np.uint64)
    assert dealt(both).closed() is keys_pair_up(both.copy()) is True


@pytest.mark.parametrize("n", [1, 5, 128, 129, 5000, 20_000])
def test_compiled_forward_keys_are_numpys(n):
    """``forward_block`` deals the forward keys and sums the balance as the numpy road does;
    ``keys_block`` makes every key."""
    rng = np.random.default_rng(n)
    triangles = rng.normal(size=(n, 3, 3))
    triangles[::7, 1] = triangles[::7, 0]                # some sides whose ends are alike
    fast, slow = kernels.ForwardBuckets(3 * n), kernels.ForwardBuckets(3 * n)
    *_, written, balance, backward, whole = KERNELS.forward_block(triangles, 0.0, 0.0, 0.0, fast.keys, fast.fill,
                                                           fast.cap, fast.shift)
    slow.add(column_edge_keys(columns(triangles)))
    assert written == int(fast.fill.sum()) == int(slow.fill.sum())
    assert (balance, backward) == (slow.balance, slow.backward)
    assert np.array_equal(fast.sorted_keys(), slow.sorted_keys())
    every = kernels.Buckets(3 * n)                       # the open road's pass: every key
    assert KERNELS.keys_block(triangles, every.keys, every.fill, every.cap, every.shift) == int(every.fill.sum())
    assert np.array_equal(every.sorted_keys(), np.sort(column_edge_keys(columns(triangles))))


def test_populated_buckets_hold_the_same_keys():
    """``populate`` (made by ``ForwardBuckets`` for the slots every bucket fills) changes no key,
    clamps ``sure`` to ``cap`` and refuses buckets that do not fit the buffer."""
    n = 100_000
    triangles = np.random.default_rng(7).normal(size=(n, 3, 3))
    fast, slow = kernels.ForwardBuckets(3 * n), kernels.ForwardBuckets(3 * n)
    assert KERNELS.populate(fast.keys, fast.fill, fast.cap, fast.shift, 10 * fast.cap) in (True, False)
    KERNELS.forward_block(triangles, 0.0, 0.0, 0.0, fast.keys, fast.fill, fast.cap, fast.shift)
    slow.add(column_edge_keys(columns(triangles)))
    assert np.array_equal(fast.sorted_keys(), slow.sorted_keys())
    with pytest.raises(ValueError):
        KERNELS.populate(fast.keys, fast.fill, fast.cap + 1, fast.shift, 1)


def test_distinct_on_many_keys():
    """Enough keys for many buckets (each sorted by the radix passes, not insertion alone)."""
    rng = np.random.default_rng(5)
    edges = np.unique(rng.integers(0, 2**63, 600_000, dtype=np.uint64))
    pairs = np.concatenate([edges << np.uint64(1), (edges << np.uint64(1)) | np.uint64(1)])
    rng.shuffle(pairs)
    assert dealt(pairs).closed() is True
    for extra in (pairs[:1], pairs[:2], pairs[[0, 1]] ^ np.uint64(1)):
        keys = np.concatenate([pairs, extra])
        assert dealt(keys).closed() is keys_pair_up(keys.copy()) is False
    assert dealt(pairs[1:]).closed() is False
    assert dealt(pairs[:0]).closed() is False               # no sides: nothing closed


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
    # Every block has a bound of exactly 0 (z from 0 up): the compiled pass leaves each to the
    # numpy code, which deals its forward keys and adds its balance itself.
    grounded = torus(120, 100, shift=(0.0, 0.0, 1.0)).astype(np.float32)
    assert grounded[..., 2].min() == 0.0
    yield "touching z = 0 (the numpy road's blocks)", grounded
    yield "touching z = 0, one face flipped", np.concatenate([grounded[:-1], grounded[-1:, ::-1]])


@pytest.mark.parametrize("name,triangles", list(variants()), ids=[name for name, _ in variants()])
def test_adversarial_meshes_same_verdicts(name, triangles):
    """With the kernels (bucketed keys, checked in place) and without (numpy's sort): the same
    verdicts, bounds and sums; and the verdict is the exact-vertex test's."""
    source = array_source("stl-binary", np.ascontiguousarray(triangles), "float32")
    assert 3 * source.face_count >= 1 << 16                 # the bucketed road
    assert_same_analysis(source)
    assert analyze(source, "x").closed is closed_exact(triangles)


def test_a_closed_mesh_never_moves_its_keys(monkeypatch):
    """A closed mesh's keys are never sorted together (that move touched every key's page a
    second time); nor are an open one's: they are grouped with the backward sides' prints
    bucket by bucket (``print_groups``; or with the other half of the keys dealt beside them,
    ``split_groups``)."""
    calls = []
    original = kernels.Buckets.sorted_keys

    def counted(self):
        calls.append(1)
        return original(self)

    monkeypatch.setattr(kernels.Buckets, "sorted_keys", counted)
    closed = analyze(array_source("stl-binary", BIG, "float32"), "x")
    assert closed.closed is True and closed.bounding is True and calls == []
    opened = analyze(array_source("stl-binary", BIG[1:], "float32"), "x")
    assert opened.closed is False and opened.bounding is False and calls == []


@given(key_sets())
def test_split_groups_are_the_groups_of_every_key(keys):
    """The forward keys' buckets and the backward keys' beside them (``Buckets.like``), scanned
    together, give ``groups`` of all the keys sorted: the same unbalanced ids, net boundary,
    sides and doubtful ids."""
    forward = dealt(keys)
    backward = kernels.Buckets.like(forward)
    backward.add(keys[(keys & np.uint64(1)) == 0])
    assert not backward.overflow
    split = KERNELS.split_groups(forward.keys, forward.fill, backward.keys, backward.fill, forward.cap,
                                 forward.shift)
    assert split == KERNELS.groups(np.sort(keys))


#: The cases of ``many_keys``.
MANY = ["holes", "doubtful only", "closed", "holes and doubtful", "soup", "misoriented"]


def many_keys(case: str) -> np.ndarray:
    """Side keys of 300,000 hashed edges, each used once each way but: some once (holes), some
    twice each way (doubtful), both, none, every edge once in one direction (a soup), or some
    twice the same way (misoriented)."""
    rng = np.random.default_rng(len(case))
    edges = np.unique(rng.integers(0, 2**63, 300_000, dtype=np.uint64))
    forward = np.ones(edges.size, dtype=np.int64)
    backward = np.ones(edges.size, dtype=np.int64)
    some = rng.choice(edges.size, 3000, replace=False)
    if case in ("holes", "holes and doubtful"):
        forward[some[:1000]], backward[some[1000:2000]] = 0, 0
    if case in ("doubtful only", "holes and doubtful"):
        forward[some[2000:2010]] = backward[some[2000:2010]] = 2
    if case == "soup":
        forward = rng.integers(0, 2, edges.size)
        backward = 1 - forward
    if case == "misoriented":
        forward[some[:500]], backward[some[:500]] = 2, 0
    keys = np.concatenate([np.repeat((edges << np.uint64(1)) | np.uint64(1), forward),
                           np.repeat(edges << np.uint64(1), backward)])
    rng.shuffle(keys)
    return keys


@pytest.mark.parametrize("case", MANY)
def test_split_groups_of_many_keys_are_the_groups_of_every_key(case):
    """Buckets of tens of thousands of keys, where ``split_groups`` sorts only the sub-buckets
    whose two directions' uses differ: the same answers as ``groups`` of every key sorted when
    a few edges are used once (holes), when no edge is unbalanced but some are used twice each
    way (the doubtful ids, from every bucket sorted whole), when every edge pairs up, when both,
    when most edges are used once (a soup: buckets sorted whole) and when edges are used twice
    the same way."""
    keys = many_keys(case)
    forward_buckets = dealt(keys)
    backward_buckets = kernels.Buckets.like(forward_buckets)
    backward_buckets.add(keys[(keys & np.uint64(1)) == 0])
    assert not backward_buckets.overflow
    split = KERNELS.split_groups(forward_buckets.keys, forward_buckets.fill, backward_buckets.keys,
                                 backward_buckets.fill, forward_buckets.cap, forward_buckets.shift)
    expected = KERNELS.groups(np.sort(keys))
    assert split == expected
    ids, _, _, doubtful = expected
    assert (len(ids) > 0) is (case not in ("doubtful only", "closed"))
    assert (doubtful is None) is (case not in ("doubtful only", "closed"))
    if case == "doubtful only":
        assert len(doubtful) == 8 * 10


@pytest.mark.parametrize("n", [1, 5, 128, 129, 5000, 20_000])
def test_compiled_backward_keys_are_numpys(n):
    """``backward_block`` deals exactly the keys with bit 0 clear of ``column_edge_keys``, to
    the buckets of the forward ones' shift."""
    block = BIG[:n]
    forward = kernels.ForwardBuckets(3 * n)
    backward = kernels.Buckets.like(forward)
    written = KERNELS.backward_block(block, backward.keys, backward.fill, backward.cap, backward.shift)
    keys = column_edge_keys(columns(block))
    expected = np.sort(keys[(keys & np.uint64(1)) == 0])
    assert written == expected.size == backward.fill.sum()
    got = np.concatenate([backward.keys[b * backward.cap:b * backward.cap + f] for b, f in enumerate(backward.fill)])
    assert np.array_equal(np.sort(got), expected)
    assert all((backward.keys[b * backward.cap:b * backward.cap + f] >> np.uint64(backward.shift) == b).all()
               for b, f in enumerate(backward.fill))
