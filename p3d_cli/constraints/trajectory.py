"""Writing a stepped scene's trajectory as CSV: one row per body per step."""

from __future__ import annotations

import contextlib
import csv
from typing import Callable, Iterator

from p3d_cli.constraints.simulation import TRAJECTORY_HEADER, trajectory_row


@contextlib.contextmanager
def trajectory_writer(path: str, inputs=()) -> Iterator[Callable]:
    """An ``on_step(t, bodies)`` callback for ``solve_scene`` that writes ``path`` as CSV.

    Columns are ``TRAJECTORY_HEADER`` (x, y, z: the centre of mass); floats in full precision.

    The file is written whole or not at all (``p3d_cli.io.atomic``): a run that fails or is
    interrupted part way leaves what was there before. A path that is one of ``inputs`` (the
    scene) is refused.

    Raises
    ------
    OutputError
        ``path`` cannot be written, or is an input.
    """
    import io

    from p3d_cli.io import atomic

    with atomic.replacing(path, inputs=inputs, what="the trajectory") as raw:
        handle = io.TextIOWrapper(raw, encoding="utf-8", newline="")
        writer = csv.writer(handle)
        writer.writerow(TRAJECTORY_HEADER)

        def record(t, bodies) -> None:
            for body in bodies:
                writer.writerow([repr(v) if isinstance(v, float) else v for v in trajectory_row(t, body)])

        yield record
        handle.flush()
        handle.detach()   # the binary file stays open for ``replacing`` to finish
