"""Baselines: a recorded state of ``props`` records, and what changed since.

A baseline is newline-delimited JSON, one ``p3d props --json`` record per line. Records are
keyed by their ``source`` relative to a root directory (``baseline_key``), so that a baseline
made in one checkout compares with another. ``compare`` lists the changes of one input:

- a quantity (``QUANTITIES``) that moved beyond ``|new - old| <= atol + rtol * scale + u_old +
  u_new``, where ``scale`` is the largest magnitude of the old value (of a whole vector or
  matrix, so that a component that is 0 in exact arithmetic is judged against the size of its
  quantity, not against its own rounding noise) and ``u_old``, ``u_new`` are the two records'
  stated rounding bounds of that component (``uncertainty``): a difference both results allow
  is never a change, whatever the tolerances;
- a value that is not a finite number (``NaN`` in a hand-edited baseline) is always a change;
- ``signed_volume`` (negative for an inward-wound mesh): a flipped winding is a change of sign;
- ``faces`` or ``closed`` that differ at all, and warning codes that appeared;
- an input that could not be read now, or was not readable then.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass
from typing import Any

from p3d_cli.errors import FormatError, ReadError, UsageError

#: Compared with a tolerance: record key -> default relative tolerance. Exact results repeat to
#: the last bit on the same input, and move by a few ulps across platforms and numpy versions
#: (summation order); 1e-9 sits far above that and far below any change a part could make.
QUANTITIES: dict[str, float] = {
    "volume": 1e-9, "signed_volume": 1e-9, "mass": 1e-9, "density": 1e-9, "center_of_mass": 1e-9,
    "inertia": 1e-9, "principal_moments": 1e-9, "bounds.min": 1e-9, "bounds.max": 1e-9,
}

#: Compared only when the baseline has them (older baselines were recorded without).
RECORDED_SINCE = ("signed_volume",)

#: Quantity -> the ``uncertainty`` key bounding its rounding error (``principal_moments``:
#: the inertia bound's Frobenius norm, which bounds every eigenvalue's move, by Weyl).
BOUNDED_BY = {"volume": "volume", "signed_volume": "volume", "mass": "mass", "center_of_mass": "center_of_mass",
              "inertia": "inertia", "principal_moments": "inertia"}

#: Compared exactly.
EXACT = ("faces", "closed")


@dataclass(frozen=True)
class Change:
    """One change of one input.

    Attributes
    ----------
    source : str
        The baseline key (the path relative to the root).
    quantity : str
        A key of ``QUANTITIES``, ``faces``, ``closed``, ``warning_codes``, or ``file`` (the input
        appeared, vanished, or could not be read).
    old, new : Any
        JSON values (None where there is none).
    relative : float or None
        For a quantity with a tolerance: ``(new - old) / |old|`` for a number, ``max |new - old|
        / scale`` for a vector or matrix.
    """

    source: str
    quantity: str
    old: Any
    new: Any
    relative: float | None = None

    def record(self) -> dict:
        """The change as JSON values: a number that is not finite (a ``NaN`` of a hand-edited
        baseline, the infinite relative change of a value that was 0) as the text ``"NaN"``,
        ``"Infinity"`` or ``"-Infinity"``, which strict JSON can hold."""
        return {"source": self.source, "quantity": self.quantity, "old": _finite(self.old),
                "new": _finite(self.new), "relative_change": _finite(self.relative)}


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if value != value else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, list):
        return [_finite(v) for v in value]
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    return value


def baseline_key(source: str, root: str, start: str | None = None) -> str:
    """``source`` relative to ``root`` with ``/`` separators; specs and ``-`` as they are.

    A relative ``source`` is relative to ``start`` (default: the working directory)."""
    if source == "-" or not _is_path(source):
        return source
    path = os.path.join(os.path.abspath(start or os.getcwd()), source)
    relative = os.path.relpath(os.path.normpath(path), os.path.abspath(root))
    return relative.replace(os.sep, "/")


def _is_path(source: str) -> bool:
    from p3d_cli.shapes import parse_spec

    try:
        return parse_spec(source) is None
    except Exception:  # noqa: BLE001 - a malformed spec is still not a path
        return False


def read_baseline(path: str, root: str) -> dict[str, dict]:
    """The records of a baseline file by key (``baseline_key`` of their ``source``; relative
    sources are taken as relative to ``root``, which is what ``p3d diff --update`` writes and
    what ``p3d props --json`` run in the root gives).

    Raises
    ------
    InputError
        The file cannot be read.
    FormatError
        A line is not a JSON object with a ``source``, or two lines have one key.
    """
    try:
        with open(path, encoding="utf-8", errors="surrogateescape") as f:
            lines = f.read().splitlines()
    except FileNotFoundError:
        raise ReadError(path, "no such file", "record one with p3d props ... --json > baseline.ndjson") from None
    except OSError as exc:
        raise ReadError(path, f"cannot be read ({exc.strerror or exc})", "check the file") from None
    out: dict[str, dict] = {}
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except ValueError:
            raise FormatError(f"{path}:{number}", "not a JSON line", "a baseline is the output of "
                              "p3d props --json, one object per line") from None
        if not isinstance(record, dict) or not isinstance(record.get("source"), str):
            raise FormatError(f"{path}:{number}", "not a p3d props record (no source)",
                              "a baseline is the output of p3d props --json")
        key = baseline_key(record["source"], root, start=root)   # a baseline's relative paths are the root's
        if key in out:
            raise FormatError(f"{path}:{number}", f"a second record for {key}", "keep one record per file")
        out[key] = record
    return out


def covered(key: str, directories: list[str]) -> bool:
    """Whether baseline ``key`` lies under one of ``directories`` (baseline keys too): a file a
    directory search would have found, had it still been there."""
    return any(d in (".", "") or key.startswith(d.rstrip("/") + "/") for d in directories)


def tolerances(values, defaults: dict[str, float], where: str) -> dict[str, float]:
    """Per-quantity tolerances: ``defaults``, then each value (a number for every quantity, or
    ``QUANTITY=NUMBER``; a mapping as a TOML table gives).

    Raises
    ------
    UsageError
    """
    out = dict(defaults)
    for value in values:
        items = value.items() if isinstance(value, dict) else [str(value).rpartition("=")[::2]]
        for name, number in items:
            try:
                x = float(number)
            except (TypeError, ValueError):
                x = math.nan
            if not x >= 0 or math.isinf(x):
                raise UsageError(where, f"{number!r} is not a non-negative number", "e.g. 1e-6 or volume=1e-6")
            if name and name not in QUANTITIES:
                raise UsageError(where, f"no quantity {name!r}", "quantities: " + ", ".join(QUANTITIES))
            out.update({name: x} if name else dict.fromkeys(QUANTITIES, x))
    return out


def compare(key: str, old: dict, new: dict, rtol: dict[str, float], atol: dict[str, float]) -> list[Change]:
    """The changes from baseline record ``old`` to current record ``new`` of one input."""
    if "error" in old or "error" in new:
        if "error" in old and "error" in new:
            return []
        return [Change(key, "file", old.get("error", "read"), new.get("error", "read"))]
    changes = []
    for name in EXACT:
        if old.get(name) != new.get(name):
            changes.append(Change(key, name, old.get(name), new.get(name)))
    for name in QUANTITIES:
        a, b = _get(old, name), _get(new, name)
        if a == b or (name in RECORDED_SINCE and name not in old):
            continue
        try:
            flat_a, flat_b = _flat(a), _flat(b)
        except (TypeError, ValueError):   # not numbers: null against a value, or a hand-edited baseline
            flat_a = flat_b = []
        if not flat_a or _shape(a) != _shape(b) or len(flat_a) != len(flat_b):
            changes.append(Change(key, name, a, b))
            continue
        bound = [x + y for x, y in zip(_bound(old, name, len(flat_a)), _bound(new, name, len(flat_a)))]
        moved, relative = _moved(flat_a, flat_b, rtol.get(name, 0.0), atol.get(name, 0.0), bound)
        if moved:
            changes.append(Change(key, name, a, b, relative))
    appeared = [c for c in new.get("warning_codes", []) if c not in old.get("warning_codes", [])]
    if appeared:
        changes.append(Change(key, "warning_codes", old.get("warning_codes", []), new.get("warning_codes", [])))
    return changes


def _get(record: dict, name: str):
    value: Any = record
    for part in name.split("."):
        value = value.get(part) if isinstance(value, dict) else None
    return value


def _shape(value) -> tuple:
    if isinstance(value, list):
        return (len(value),) + (_shape(value[0]) if value else ())
    return ()


def _flat(value) -> list[float]:
    if isinstance(value, list):
        return [x for v in value for x in _flat(v)]
    return [float(value)]


def _bound(record: dict, name: str, size: int) -> list[float]:
    """The record's stated rounding bound of each component of quantity ``name`` (0 where it
    states none, or states something that is not a non-negative finite number)."""
    zero = [0.0] * size
    uncertainty = record.get("uncertainty")
    if name not in BOUNDED_BY or not isinstance(uncertainty, dict):
        return zero
    value = uncertainty.get(BOUNDED_BY[name])
    try:
        flat = _flat(value)
    except (TypeError, ValueError):
        return zero
    if not all(math.isfinite(x) and x >= 0 for x in flat):
        return zero
    if name == "principal_moments":
        return [math.sqrt(sum(x * x for x in flat))] * size
    return flat if len(flat) == size else zero


def _moved(a: list[float], b: list[float], rtol: float, atol: float,
           bound: list[float] | None = None) -> tuple[bool, float | None]:
    """Whether any component moved beyond ``atol + rtol * scale + bound``, and the relative change."""
    if not all(math.isfinite(x) for x in a + b):
        # NaN equals nothing, so it never passes a tolerance test written as "within": a value that
        # is not finite is a change, unless both records hold the same infinity there.
        same = all(x == y or (math.isfinite(x) and math.isfinite(y) and abs(x - y) <= atol) for x, y in zip(a, b))
        return not same, None
    bound = bound or [0.0] * len(a)
    scale = max(abs(x) for x in a)
    difference = max(abs(x - y) for x, y in zip(a, b))
    relative = difference / scale if scale > 0 else (math.inf if difference else 0.0)
    if len(a) == 1 and scale > 0:
        relative = (b[0] - a[0]) / scale          # a single number's change keeps its sign
    moved = any(abs(x - y) > atol + rtol * scale + u for x, y, u in zip(a, b, bound))
    return moved, relative


__all__ = ["Change", "EXACT", "QUANTITIES", "baseline_key", "compare", "covered", "read_baseline", "tolerances"]
