"""The serialisers every command shares: one JSON writer, numbers and vectors for people, bare
fields for the shell, CSV rows. Each command's own records and tables live with the command."""

from __future__ import annotations

import json
import math

import numpy as np


def jsonable(value):
    """Plain Python values for ``json``: arrays become (nested) lists of floats."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (np.floating, np.integer, np.bool_)):
        return value.item()
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    return value


def dumps(record: dict) -> str:
    """One line of JSON; floats keep full precision (Python's repr round-trips float64)."""
    return json.dumps(jsonable(record), ensure_ascii=False, allow_nan=False)


def number(x) -> str:
    """A float for people: 10 significant digits, never ``0.000000`` for a small non-zero value."""
    if x is None:
        return "-"
    x = float(x)
    if x == 0.0:
        return "0"
    if not math.isfinite(x):
        return repr(x)
    return f"{x:.10g}"


def vector(v) -> str:
    return "-" if v is None else "  ".join(f"{number(x):>17}" for x in np.asarray(v).reshape(-1))


def field_value(record: dict, name: str):
    """``record[name]``, with dots for nesting (``bounds.min``); KeyError when absent."""
    value = record
    for part in name.split("."):
        if not isinstance(value, dict) or part not in value:
            raise KeyError(name)
        value = value[part]
    return value


def bare(value) -> str:
    """A field for shell use: numbers in full precision, vectors space-separated, one matrix row
    after another."""
    value = jsonable(value)
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list):
        return " ".join(bare(v) for v in value)
    return str(value)


def csv_line(values) -> str:
    """One CSV row (RFC 4180 quoting), without its line end: floats in full precision (repr),
    booleans as true/false, None and missing values empty."""
    import csv
    import io

    cells = []
    for value in values:
        value = jsonable(value)
        if value is None:
            cells.append("")
        elif isinstance(value, bool):
            cells.append("true" if value else "false")
        elif isinstance(value, float):
            cells.append(repr(value))
        else:
            cells.append(str(value))
    buffer = io.StringIO()
    csv.writer(buffer, lineterminator="").writerow(cells)
    return buffer.getvalue()
