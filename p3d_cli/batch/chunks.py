"""Cutting a batch into chunks of files for a Dask cluster, sized from the files' sizes.

A Dask task costs a few milliseconds of scheduler, network and client time, about what
``p3d props`` spends on a whole 0.26 MB mesh; one task per file made a batch of small files
3-4 times slower than ``--jobs``. A chunk of files per task pays that cost once per chunk.

The chunks are contiguous runs of the inputs, in order, cut by guided self-scheduling
(Polychronopoulos and Kuck, "Guided self-scheduling", IEEE Trans. Computers 36(12), 1987):
each chunk gets a share ``1 / (PER_SLOT * slots)`` of the work still to cut, so early chunks
are big (few tasks) and the last ones small (the workers finish together), and there are
always several chunks per worker thread, so results keep streaming back. The share is held
between ``MIN_WEIGHT`` (a task's work should dwarf its overhead) and ``MAX_WEIGHT`` (results
of a huge batch still come back every second or so).

A file's work is taken as its size plus ``PER_FILE``, the fixed cost of opening, sniffing and
reporting any file, expressed in bytes: p3d reads meshes at roughly 100 MB/s a core, and the
fixed part is under a millisecond.
"""

from __future__ import annotations

import os
from typing import Callable, Sequence

PER_FILE = 64 * 1024
MIN_WEIGHT = 8 * 1024 * 1024
MAX_WEIGHT = 128 * 1024 * 1024
PER_SLOT = 4


def file_weights(paths: Sequence[str]) -> list[int]:
    """Each path's size plus ``PER_FILE``; a path that cannot be read weighs ``PER_FILE``
    (its error is found and reported by the worker that reads it)."""
    out = []
    for path in paths:
        try:
            size = os.stat(path).st_size
        except (OSError, ValueError):  # missing, unreadable, or a NUL in the name
            size = 0
        out.append(size + PER_FILE)
    return out


def plan_chunks(weights: Sequence[int], slots: int) -> list[range]:
    """Contiguous index ranges covering ``range(len(weights))`` in order, each a chunk.

    Parameters
    ----------
    weights : sequence of int
        Each input's estimated work (``file_weights``).
    slots : int
        Tasks the cluster runs at once (its worker threads); at least 1 is assumed.

    Returns
    -------
    list of range
        Non-empty, in order, together holding every index exactly once.
    """
    slots = max(1, slots)
    remaining = sum(weights)
    chunks: list[range] = []
    start = held = 0
    target = _target(remaining, slots)
    for i, weight in enumerate(weights):
        held += weight
        if held >= target:
            chunks.append(range(start, i + 1))
            remaining -= held
            start, held = i + 1, 0
            target = _target(remaining, slots)
    if start < len(weights):
        chunks.append(range(start, len(weights)))
    return chunks


def _target(remaining: int, slots: int) -> float:
    return min(MAX_WEIGHT, max(MIN_WEIGHT, remaining / (PER_SLOT * slots)))


def run_chunk(task: tuple[Callable, object, list]) -> list:
    """``[run((work, item)) for item in items]`` for ``task = (run, work, items)``: the Dask
    task of one chunk (``run`` is the runner's error-catching wrapper, so nothing raises)."""
    run, work, items = task
    return [run((work, item)) for item in items]
