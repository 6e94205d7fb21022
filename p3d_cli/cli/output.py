"""Formatting results: one JSON serialiser, human-readable tables, bare fields."""

from __future__ import annotations

import json
import math

import numpy as np

from p3d_cli.results import PropsResult

INERTIA_CONVENTION = "positive tensor: Ixx = ∫(y²+z²) dm, Ixy = -∫xy dm"


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


def props_record(result: PropsResult) -> dict:
    """The JSON object of ``p3d props`` for one input (stable keys)."""
    p, f = result.properties, result.facts
    record = {
        "source": f.source,
        "format": f.format,
        "method": result.method,
        "faces": f.faces,
        "closed": f.closed,
        "volume": p.volume,
        "mass": p.mass,
        "density": p.density,
        "center_of_mass": p.center_of_mass,
        "inertia": p.inertia,
        "inertia_origin": p.inertia_origin,
        "principal_moments": p.principal_moments,
        "principal_axes": p.principal_axes,
        "second_moments": p.second_moments,
        "bounds": None if f.bounds is None else {"min": f.bounds.min, "max": f.bounds.max},
        "coordinate_dtype": f.coordinate_dtype,
        "inertia_convention": INERTIA_CONVENTION,
        "warnings": list(result.warnings),
        "uncertainty": result.uncertainty,
    }
    if p.about is not None:
        record["about"] = p.about
        record["inertia_about"] = p.inertia_about
    record.update(result.details)
    return record


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


def props_table(result: PropsResult) -> str:
    """A readable block for one input."""
    p, f = result.properties, result.facts
    closed = {True: "yes", False: "NO", None: "n/a"}[f.closed]
    lines = [
        f"{f.source}  ({f.format}, {f.faces} faces, closed: {closed}, method: {result.method})",
        f"  volume            {number(p.volume)}",
        f"  density           {number(p.density)}",
        f"  mass              {number(p.mass)}",
        f"  center of mass    {vector(p.center_of_mass)}",
    ]
    if p.inertia is None:
        lines.append("  inertia           - (no volume)")
    else:
        lines.append("  inertia about the centre of mass (" + INERTIA_CONVENTION + ")")
        lines += [f"                    {vector(row)}" for row in p.inertia]
        lines.append("  inertia about the origin")
        lines += [f"                    {vector(row)}" for row in p.inertia_origin]
        if p.inertia_about is not None:
            lines.append(f"  inertia about ({', '.join(number(x) for x in p.about)})")
            lines += [f"                    {vector(row)}" for row in p.inertia_about]
        lines.append(f"  principal moments {vector(p.principal_moments)}")
        lines.append("  principal axes (rows; right-handed)")
        lines += [f"                    {vector(row)}" for row in p.principal_axes]
    if f.bounds is not None:
        lines.append(f"  bounds min        {vector(f.bounds.min)}")
        lines.append(f"  bounds max        {vector(f.bounds.max)}")
    return "\n".join(lines)


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


#: Columns of ``p3d props --csv``: inertia about the centre of mass, positive tensor convention.
PROPS_CSV_COLUMNS = ("source", "format", "method", "faces", "closed", "volume", "mass", "density",
                     "com_x", "com_y", "com_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz",
                     "warnings", "error")


def props_row(record: dict) -> list:
    """The ``--csv`` cells of a ``props_record`` (or of an error record), in column order."""
    row = dict.fromkeys(PROPS_CSV_COLUMNS)
    row.update({k: v for k, v in record.items() if k in row})
    com, inertia = record.get("center_of_mass"), record.get("inertia")
    if com is not None:
        row["com_x"], row["com_y"], row["com_z"] = (float(x) for x in com)
    if inertia is not None:
        i = np.asarray(inertia)
        row.update(ixx=i[0, 0], iyy=i[1, 1], izz=i[2, 2], ixy=i[0, 1], ixz=i[0, 2], iyz=i[1, 2])
    row["warnings"] = " | ".join(record.get("warnings") or []) or None
    return [row[k] for k in PROPS_CSV_COLUMNS]
