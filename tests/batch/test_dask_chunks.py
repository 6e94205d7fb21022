"""Dask batches in chunks of files: the plan covers every input once, in order, sized from the
file sizes; on a cluster every result is delivered once, in order, and a worker that dies on
one input of a chunk costs only that input."""

from __future__ import annotations

import os
import time

import pytest
from hypothesis import given
from hypothesis import strategies as st

from p3d_cli.batch import chunks, run_each


def weight_of(span: range, weights: list[int]) -> int:
    return sum(weights[i] for i in span)


@given(st.lists(st.integers(0, 300 * 2**20), max_size=300), st.integers(0, 16))
def test_plan_covers_every_input_once_in_order(weights, slots):
    plan = chunks.plan_chunks(weights, slots)
    assert [i for span in plan for i in span] == list(range(len(weights)))
    assert all(len(span) > 0 and span.step == 1 for span in plan)
    # Every chunk but the last was cut as soon as it reached its share, which is at least
    # MIN_WEIGHT: so no chunk but the last is lighter than that, nor heavier than
    # MAX_WEIGHT plus its last input.
    for span in plan[:-1]:
        assert weight_of(span, weights) >= chunks.MIN_WEIGHT
    for span in plan:
        assert weight_of(span[:-1], weights) < chunks.MAX_WEIGHT


def test_plan_for_many_small_files_keeps_several_chunks_per_slot():
    weights = [260_084 + chunks.PER_FILE] * 1000  # 1,000 binary STL files of 5,120 faces
    plan = chunks.plan_chunks(weights, 2)
    assert len(plan) >= chunks.PER_SLOT * 2
    assert len(plan) <= 1000 * weights[0] // chunks.MIN_WEIGHT + 1  # no chunk under MIN_WEIGHT but the last
    sizes = [len(span) for span in plan]
    assert sizes[0] == -(-sum(weights) // (chunks.PER_SLOT * 2) // weights[0])  # the first share, rounded up
    assert sizes[:-1] == sorted(sizes[:-1], reverse=True)  # guided: shares shrink with the work left


def test_plan_of_nothing_and_of_one():
    assert chunks.plan_chunks([], 4) == []
    assert chunks.plan_chunks([10], 4) == [range(0, 1)]


def test_file_weights_are_sizes_plus_a_fixed_cost(tmp_path):
    (tmp_path / "a.stl").write_bytes(b"x" * 1234)
    missing = str(tmp_path / "missing.stl")
    assert chunks.file_weights([str(tmp_path / "a.stl"), missing, "bad\0name"]) == \
        [1234 + chunks.PER_FILE, chunks.PER_FILE, chunks.PER_FILE]


def test_run_chunk_runs_each_item_through_the_wrapper():
    assert chunks.run_chunk((lambda task: task[0](task[1]), str.upper, ["a", "b"])) == ["A", "B"]


# --- on real clusters ---------------------------------------------------------------------------


@pytest.fixture
def threaded_cluster():
    if os.environ.get("CI") != "true":
        pytest.importorskip("dask.distributed")
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=":0") as cluster:
        yield cluster.scheduler_address
    time.sleep(0.1)


def test_many_chunks_deliver_every_result_once_in_order(threaded_cluster, monkeypatch):
    planned = []
    real_plan = chunks.plan_chunks

    def plan(weights, slots):
        planned.append((slots, real_plan(weights, slots)))
        return planned[-1][1]

    monkeypatch.setattr(chunks, "MIN_WEIGHT", 1)  # small chunks: many of them for 200 inputs
    monkeypatch.setattr(chunks, "plan_chunks", plan)
    items = [f"item{i:03}" for i in range(200)]
    out = list(run_each(items, str.upper, dask=threaded_cluster))
    assert [o.source for o in out] == items
    assert [o.result for o in out] == [item.upper() for item in items]
    assert all(o.error is None for o in out)
    (slots, spans), = planned
    assert slots == 2 and len(spans) > 8


def test_a_worker_dying_on_one_input_of_a_chunk_costs_only_that_input():
    distributed = pytest.importorskip("dask.distributed")
    import dask

    def work(item):  # a closure: pickled by value, so the worker processes need not import tests
        if item == "bad":
            os._exit(1)  # as the out-of-memory killer would end it
        return item * 2

    items = ["a", "b", "bad", "c", "d"]
    # A task that kills a worker once is declared lost (KilledWorker) at once, not after three
    # more deaths: the test stays quick, and the chunk and then "bad" alone each kill one worker.
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                      dashboard_address=":0") as cluster:
            out = list(run_each(items, work, dask=cluster.scheduler_address))
    assert [o.source for o in out] == items
    assert [o.result for o in out] == ["aa", "bb", None, "cc", "dd"]
    assert [o.error is None for o in out] == [True, True, False, True, True]
    assert out[2].error.exit_code == 2
    assert out[2].error.message.startswith("bad: not done: every Dask worker that tried it died (1 tried); ")
