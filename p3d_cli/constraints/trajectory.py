"""Writing a stepped scene's trajectory as CSV: one row per body per step."""

from __future__ import annotations

import contextlib
import csv
from typing import Callable, Iterator

from p3d_cli.constraints.simulation import TRAJECTORY_HEADER, trajectory_row
from p3d_cli.errors import UsageError


@contextlib.contextmanager
def trajectory_writer(path: str) -> Iterator[Callable]:
    """An ``on_step(t, bodies)`` callback for ``solve_scene`` that writes ``path`` as CSV.

    Columns are ``TRAJECTORY_HEADER`` (x, y, z: the centre of mass); floats in full precision.

    Raises
    ------
    UsageError
        ``path`` cannot be written.
    """
    try:
        handle = open(path, "w", newline="", encoding="utf-8")
    except OSError as exc:
        raise UsageError("trajectory", f"cannot write {path!r} ({exc.strerror or exc})",
                         "choose a writable path") from None
    with handle:
        writer = csv.writer(handle)
        writer.writerow(TRAJECTORY_HEADER)

        def record(t, bodies) -> None:
            for body in bodies:
                writer.writerow([repr(v) if isinstance(v, float) else v for v in trajectory_row(t, body)])

        yield record
