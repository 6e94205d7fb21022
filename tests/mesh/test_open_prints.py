"""``p3d props``' open road by prints (issue 32): the first pass keeps 32 bits of each backward
side's key (its *print*) beside the forward keys; an open mesh's unbalanced edges are found by
grouping the forward keys and the prints by print id (``print_groups``), picking the sides of
the unbalanced print groups in one more pass with their keys (``pick_sides(..., low, keys)``),
grouping those exactly and checking them against the whole mesh's balance
(``boundary_sides.sides_of_prints``). Checked against the road by every key (the backward keys
dealt in a pass of their own, ``split_groups``, then ``unbalanced_sides``), against ``groups``
of the print ids, and against the numpy code; and the balance check is shown to catch a print
group lost to a coincidence."""

from __future__ import annotations

import numpy as np
import pytest

from helpers.kernels import needs_kernels
from p3d_cli.io.source import array_source
from p3d_cli.mesh import boundary_sides, kernels, open_groups
from p3d_cli.mesh.analysis import analyze
from p3d_cli.mesh.closed import column_edge_keys
from p3d_cli.mesh.columns import columns
from p3d_cli.mesh.splitmix import mix
from test_closed_buckets import BIG, MANY, dealt, many_keys
from test_kernels import assert_same_analysis, bits

KERNELS = kernels.KERNELS
pytestmark = needs_kernels


def prints_of(keys: np.ndarray, shift: int) -> np.ndarray:
    """The prints of keys: the 32 bits below the buckets' bits."""
    return ((keys >> np.uint64(shift - 32)) & np.uint64(0xFFFFFFFF)).astype(np.uint32)


def deal_prints(buckets: kernels.ForwardBuckets, backward: np.ndarray) -> None:
    """Deal backward keys' prints to ``buckets``' print buckets, as ``forward_block`` does."""
    bucket = (backward >> np.uint64(buckets.shift)).astype(np.int64)
    counts = np.bincount(bucket, minlength=buckets.fill.size)
    assert (buckets.print_fill + counts <= buckets.cap).all()
    order = np.argsort(bucket, kind="stable")
    bucket = bucket[order]
    rank = np.arange(bucket.size) - (np.cumsum(counts) - counts)[bucket]
    buckets.prints[bucket * buckets.cap + buckets.print_fill[bucket] + rank] = prints_of(backward[order],
                                                                                        buckets.shift)
    buckets.print_fill += counts


def bucket_contents(values: np.ndarray, fill: np.ndarray, cap: int) -> list[np.ndarray]:
    return [np.sort(values[b * cap:b * cap + f]) for b, f in enumerate(fill)]


@pytest.mark.parametrize("n", [1, 5, 128, 129, 5000, 20_000])
def test_forward_block_deals_the_backward_sides_prints(n):
    """The prints ``forward_block`` deals are the 32 bits below the bucket bits of exactly the
    keys with bit 0 clear of ``column_edge_keys``, each in its key's bucket; the forward keys,
    balance and backward count are those it makes without prints."""
    rng = np.random.default_rng(n)
    triangles = rng.normal(size=(n, 3, 3))
    triangles[::7, 1] = triangles[::7, 0]                # some sides whose ends are alike
    fast, plain = kernels.ForwardBuckets(3 * n), kernels.ForwardBuckets(3 * n)
    *_, written, balance, backward, whole = KERNELS.forward_block(
        triangles, 0.0, 0.0, 0.0, fast.keys, fast.fill, fast.cap, fast.shift, fast.prints, fast.print_fill)
    assert whole is True
    assert KERNELS.forward_block(triangles, 0.0, 0.0, 0.0, plain.keys, plain.fill, plain.cap,
                                 plain.shift)[-4:] == (written, balance, backward, False)
    assert np.array_equal(fast.sorted_keys(), plain.sorted_keys())
    keys = column_edge_keys(columns(triangles))
    back = keys[(keys & np.uint64(1)) == 0]
    assert backward == back.size == int(fast.print_fill.sum())
    expected = kernels.ForwardBuckets(3 * n)
    deal_prints(expected, back)
    assert np.array_equal(expected.print_fill, fast.print_fill)
    for got, want in zip(bucket_contents(fast.prints, fast.print_fill, fast.cap),
                         bucket_contents(expected.prints, expected.print_fill, expected.cap)):
        assert np.array_equal(got, want)


def test_a_full_print_bucket_says_the_prints_are_not_whole():
    """A print that finds its bucket full is dropped and ``forward_block`` says so (the open
    road then takes the backward keys); the forward keys are dealt as ever."""
    triangles = BIG[:5000]
    fast, plain = kernels.ForwardBuckets(3 * 5000), kernels.ForwardBuckets(3 * 5000)
    fast.print_fill[:] = fast.cap
    result = KERNELS.forward_block(triangles, 0.0, 0.0, 0.0, fast.keys, fast.fill, fast.cap, fast.shift,
                                   fast.prints, fast.print_fill)
    assert result[-1] is False and (fast.print_fill == fast.cap).all()
    KERNELS.forward_block(triangles, 0.0, 0.0, 0.0, plain.keys, plain.fill, plain.cap, plain.shift)
    assert np.array_equal(fast.sorted_keys(), plain.sorted_keys())


def test_print_buckets_that_do_not_fit_are_refused():
    fast = kernels.ForwardBuckets(3 * 100)
    with pytest.raises(ValueError):
        KERNELS.forward_block(BIG[:100], 0.0, 0.0, 0.0, fast.keys, fast.fill, fast.cap, fast.shift,
                              fast.prints[:-2], fast.print_fill)
    with pytest.raises(ValueError):
        KERNELS.print_groups(fast.keys, fast.fill, fast.prints.view(np.int32)[:-1], fast.print_fill, fast.cap,
                             fast.shift)


@pytest.mark.parametrize("case", MANY)
def test_print_groups_are_the_groups_of_the_print_ids(case):
    """``print_groups`` of the forward keys and the backward prints gives ``groups`` of every
    side's print id (``key >> (shift - 32)``, its direction kept): ids, net boundary, sides and
    doubtful ids alike; and where no two edges share a print id, its ids are the print ids of
    the edges ``groups`` of the full keys finds unbalanced."""
    keys = many_keys(case)
    buckets = dealt(keys)
    deal_prints(buckets, keys[(keys & np.uint64(1)) == 0])
    low = np.uint64(buckets.shift - 32)
    got = KERNELS.print_groups(buckets.keys, buckets.fill, buckets.prints, buckets.print_fill, buckets.cap,
                               buckets.shift)
    as_keys = ((keys >> low) << np.uint64(1)) | (keys & np.uint64(1))
    assert got == KERNELS.groups(np.sort(as_keys))
    exact = np.frombuffer(KERNELS.groups(np.sort(keys))[0], dtype=np.uint64) >> (low - np.uint64(1))
    ids, counts = np.unique(np.unique(keys >> np.uint64(1)) >> (low - np.uint64(1)), return_counts=True)
    shared = ids[counts > 1]                # print ids of more than one edge (2**34 ids here)
    if case != "soup":
        assert not np.isin(exact, shared).any()
        assert np.array_equal(np.frombuffer(got[0], dtype=np.uint64), exact)


def test_two_edges_sharing_a_print_id_can_hide_each_other():
    """Why the road checks the balance: two edges whose keys share their print id, one used
    only forward and one only backward, make one balanced print group, and ``print_groups``
    finds nothing there while ``groups`` of the keys finds both."""
    rng = np.random.default_rng(3)
    edges = np.unique(rng.integers(0, 2**63, 100_000, dtype=np.uint64))
    twin = edges[:1] ^ np.uint64(1)                      # differs from edges[0] in its lowest bit only
    assert twin[0] not in edges
    # every edge once each way, but edges[0] only forward and its twin only backward
    keys = np.concatenate([(edges << np.uint64(1)) | np.uint64(1), edges[1:] << np.uint64(1), twin << np.uint64(1)])
    buckets = dealt(keys)
    deal_prints(buckets, keys[(keys & np.uint64(1)) == 0])
    printed = KERNELS.print_groups(buckets.keys, buckets.fill, buckets.prints, buckets.print_fill, buckets.cap,
                                   buckets.shift)
    assert printed[0] == b"" and printed[3] is not None      # nothing unbalanced by print id
    assert np.frombuffer(KERNELS.groups(np.sort(keys))[0], dtype=np.uint64).size == 2


@pytest.mark.parametrize("low", [1, 20, 27])
def test_pick_sides_by_print_ids_gives_the_sides_and_their_keys(low):
    """``pick_sides`` with ``low`` picks the sides whose ``key >> low`` is in the ids, in the
    order of ``unbalanced_sides`` (slot, then face), and writes their keys."""
    block = BIG[:3000]
    cols = columns(block)
    keys = column_edge_keys(cols)                    # slot-major, as the sides are picked
    rng = np.random.default_rng(low)
    chosen = np.unique(keys[rng.choice(keys.size, 200, replace=False)] >> np.uint64(low))
    members = boundary_sides.Members(chosen, 64 - low)
    out, made = np.empty((3 * len(block), 6)), np.empty(3 * len(block), dtype=np.uint64)
    n = KERNELS.pick_sides(block, chosen, members.bits, int(members.shift), *members.starts(), out, low, made)
    hit = np.isin(keys >> np.uint64(low), chosen)
    assert n == hit.sum() and np.array_equal(made[:n], keys[hit])
    slot, face = np.divmod(np.flatnonzero(hit), len(block))
    assert np.array_equal(out[:n, :3], cols[slot, :, face] + 0.0)
    assert np.array_equal(out[:n, 3:], cols[(slot + 1) % 3, :, face] + 0.0)
    for bad in (0, 63):
        with pytest.raises(ValueError):
            KERNELS.pick_sides(block, chosen, members.bits, int(members.shift), *members.starts(), out, bad, made)


def open_variants():
    t = BIG
    flipped = t[:, ::-1]
    rng = np.random.default_rng(11)
    yield "every 100th face removed", np.delete(t, np.s_[::100], axis=0)
    yield "one face removed", t[1:]
    yield "a strip removed", t[500:]
    yield "one face flipped", np.concatenate([t[:5], flipped[5:6], t[6:]])
    yield "a face twice (its edges used three times)", np.concatenate([t, t[10:11]])
    yield "holes, shuffled", np.delete(t, np.s_[::37], axis=0)[rng.permutation(len(t) - len(t[::37]))]
    yield "holes and a sliver side", np.concatenate([t[1:], np.stack([t[0, 0], t[0, 0], t[0, 1]])[None]])
    yield "holes and a face and its flip", np.concatenate([t[2:], t[10:11], flipped[10:11]])


def roads_taken(monkeypatch) -> list:
    """Spy on the road by prints: the list gets each call's answer (None: the other road)."""
    taken = []
    original = open_groups.printed_groups

    def spy(*args):
        found = original(*args)
        taken.append(found)
        return found

    monkeypatch.setattr(open_groups, "printed_groups", spy)
    return taken


def road_by_keys(monkeypatch):
    """Switch the road by prints off (the road by every key, as before it)."""
    monkeypatch.setattr(open_groups, "printed_groups", lambda *args: None)


def assert_same(a, b):
    assert (a.closed, a.bounding, a.boundary_edges, a.face_count) == (b.closed, b.bounding, b.boundary_edges,
                                                                     b.face_count)
    assert bits(a.moments.volume) == bits(b.moments.volume)
    for name in ("center", "central"):
        if getattr(b.moments, name) is not None:
            assert np.array_equal(bits(getattr(a.moments, name)), bits(getattr(b.moments, name)))
    for name in ("volume", "center", "central"):
        assert np.array_equal(bits(getattr(a.moments.errors, name)), bits(getattr(b.moments.errors, name)))


@pytest.mark.parametrize("name,triangles", list(open_variants()), ids=[name for name, _ in open_variants()])
def test_open_meshes_by_prints_as_by_every_key(name, triangles, monkeypatch):
    """The road by prints is taken on these open meshes and gives the bits of the road by every
    key (its ``Unbalanced``, its sides in the same blocks and order, so the same terms), and the
    numpy code's."""
    source = array_source("stl-binary", np.ascontiguousarray(triangles), "float32")
    with monkeypatch.context() as m:
        taken = roads_taken(m)
        printed = analyze(source, "x")
    assert len(taken) == 1 and taken[0] is not None and printed.closed is False
    with monkeypatch.context() as m:
        road_by_keys(m)
        assert_same(printed, analyze(source, "x"))
    assert_same_analysis(source)


def test_the_sides_picked_are_those_of_unbalanced_sides(monkeypatch):
    """``sides_of_prints``' ``Unbalanced`` and sides, block by block, are ``unbalanced_groups``
    of every key and the compiled ``unbalanced_sides``' chunks."""
    triangles = np.delete(BIG, np.s_[::50], axis=0)
    blocks = [triangles[i:i + 4000] for i in range(0, len(triangles), 4000)]
    keys = np.concatenate([column_edge_keys(columns(b)) for b in blocks])
    unbalanced = boundary_sides.unbalanced_groups(np.sort(keys))
    buckets = kernels.ForwardBuckets(keys.size)
    for b in blocks:
        KERNELS.forward_block(b, 0.0, 0.0, 0.0, buckets.keys, buckets.fill, buckets.cap, buckets.shift,
                              buckets.prints, buckets.print_fill)
    forward = keys[(keys & np.uint64(1)) == 1]
    g = mix(keys | np.uint64(1))
    balance = (int(g[(keys & np.uint64(1)) == 1].sum(dtype=np.uint64))
               - int(g[(keys & np.uint64(1)) == 0].sum(dtype=np.uint64))) % (1 << 64)
    prints, _, count, doubtful = KERNELS.print_groups(buckets.keys, buckets.fill, buckets.prints, buckets.print_fill,
                                                      buckets.cap, buckets.shift)
    assert doubtful is None
    found = boundary_sides.sides_of_prints(iter(blocks), np.frombuffer(prints, dtype=np.uint64).copy(),
                                     buckets.shift - 32, count, balance, keys.size)
    assert found is not None
    got, picked = found
    assert np.array_equal(got.ids, unbalanced.ids)
    assert (got.edges, got.sides, got.total) == (unbalanced.edges, unbalanced.sides, unbalanced.total)
    assert forward.size + int(buckets.print_fill.sum()) == keys.size
    chunks = list(boundary_sides.unbalanced_sides(iter(blocks), unbalanced.ids))
    again = list(boundary_sides.block_sides(picked))
    assert len(chunks) == len(again)
    for (u, v), (x, y) in zip(chunks, again):
        assert np.array_equal(u, x) and np.array_equal(v, y)
    # a balance that is not the mesh's: an unbalanced edge would be missing; nothing is answered
    assert boundary_sides.sides_of_prints(iter(blocks), np.frombuffer(prints, dtype=np.uint64).copy(),
                                    buckets.shift - 32, count, balance ^ 1, keys.size) is None


def test_a_print_group_lost_is_caught_by_the_balance(monkeypatch):
    """A print group that a coincidence hid (here: one of the print ids dropped before the
    pick) leaves its edges' share out of the picked sides' balance: ``sides_of_prints`` answers
    nothing and the mesh takes the road by every key, with the same result."""
    source = array_source("stl-binary", np.ascontiguousarray(np.delete(BIG, np.s_[::100], axis=0)), "float32")
    answers = []
    original = boundary_sides.sides_of_prints

    def dropped(blocks, prints, low, count, balance, total):
        blocks = list(blocks)
        keys = np.concatenate([column_edge_keys(columns(b)) for b in blocks])
        lost = int((keys >> np.uint64(low) == prints[0]).sum())     # the sides of the dropped group
        found = original(iter(blocks), prints[1:], low, count - lost, balance, total)
        answers.append(found)
        return found

    monkeypatch.setattr(open_groups, "sides_of_prints", dropped)
    split = []
    split_groups = KERNELS.split_groups

    class Spy:
        def __getattr__(self, name):
            return getattr(KERNELS, name)

        def split_groups(self, *args):
            split.append(1)
            return split_groups(*args)

    monkeypatch.setattr(kernels, "KERNELS", Spy())
    result = analyze(source, "x")
    assert answers == [None] and split == [1]
    monkeypatch.setattr(open_groups, "sides_of_prints", original)
    assert_same(result, analyze(source, "x"))


def test_a_soup_takes_the_road_by_every_key(monkeypatch):
    """Where most sides are in unbalanced print groups (a soup of loose faces), their sides are
    not kept in memory: the road by every key takes the mesh, as before."""
    triangles = np.random.default_rng(2).normal(size=(30_000, 3, 3)).astype(np.float32)
    source = array_source("stl-binary", triangles, "float32")
    with monkeypatch.context() as m:
        taken = roads_taken(m)
        result = analyze(source, "x")
    assert taken == [None] and result.bounding is False
    assert_same_analysis(source)


@pytest.mark.parametrize("name", ["common3d__horse.ply", "trimeshes__rockerarm.stl"])
def test_real_meshes_with_holes_by_prints(real_meshes, name, tmp_path, monkeypatch):
    """Two real scans, every 50th face removed, as triangles in memory and as an indexed binary
    PLY (the first pass through the indexed blocks, the pick through the triangles): the road
    by prints is taken and gives the bits of the road by every key and of the numpy code."""
    import trimesh

    from p3d_cli.io import load_mesh

    source = load_mesh(str(real_meshes / name))
    indexed = source.indexed_arrays()
    if indexed is None:                                  # an STL: its corners as they are
        vertices = np.concatenate(list(source.read_blocks())).reshape(-1, 3)
        indexed = vertices, [np.arange(len(vertices)).reshape(-1, 3)]
    vertices, pieces = indexed
    faces = np.delete(np.concatenate(pieces), np.s_[::50], axis=0)
    assert 3 * len(faces) >= 1 << 16                     # the bucketed road
    path = tmp_path / "holed.ply"
    trimesh.Trimesh(vertices, faces, process=False).export(path)
    for source in (array_source("stl-binary", np.ascontiguousarray(vertices[faces]), "float32"),
                   load_mesh(str(path))):
        with monkeypatch.context() as m:
            taken = roads_taken(m)
            printed = analyze(source, "x")
        assert len(taken) == 1 and taken[0] is not None and printed.closed is False and printed.bounding is False
        with monkeypatch.context() as m:
            road_by_keys(m)
            assert_same(printed, analyze(source, "x"))
        assert_same_analysis(source)


def test_meshes_of_many_buckets_keep_no_prints(monkeypatch):
    """Past ``PRINT_BUCKETS`` buckets (about 1.4M faces) no prints are kept or dealt, and an
    open mesh takes the road by every key, with the same result."""
    large = kernels.ForwardBuckets(3 * 2_000_000)
    assert large.fill.size > large.PRINT_BUCKETS and large.whole is False and large.prints.size == 0
    source = array_source("stl-binary", np.ascontiguousarray(np.delete(BIG, np.s_[::100], axis=0)), "float32")
    printed = analyze(source, "x")
    monkeypatch.setattr(kernels.ForwardBuckets, "PRINT_BUCKETS", 0)
    calls = []
    monkeypatch.setattr(open_groups, "printed_groups", lambda *args: calls.append(1))
    assert_same(printed, analyze(source, "x"))
    assert calls == []
