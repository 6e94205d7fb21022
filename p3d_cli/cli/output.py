"""The serialisers every command shares: one JSON writer, numbers and vectors for people, bare
fields for the shell, CSV rows. Each command's own records and tables live with the command."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

# The JSON writer is the library's (``to_json`` of every result); this module adds the record's kind.
from p3d_cli.records import SCHEMA_VERSION, dumps, jsonable  # noqa: F401 (used by every command)


#: The kinds of record, each with its schema file.
RECORD_KINDS = ("props", "bounds", "check", "diff", "solve", "summary", "config", "repair")


def record_line(kind: str, record: dict) -> str:
    """One ``--json`` record of ``kind`` (``RECORD_KINDS``) as a line of JSON, with its
    ``schema_version`` first. Every record p3d prints or writes goes through here."""
    return dumps({"schema_version": SCHEMA_VERSION, **{k: v for k, v in record.items() if k != "schema_version"}})


def schema(kind: str) -> dict:
    """The JSON Schema of records of ``kind`` (shipped in the package)."""
    from importlib.resources import files

    return json.loads(files("p3d_cli").joinpath("schemas").joinpath(f"{kind}.json").read_text(encoding="utf-8"))


def number(x, precision: int = 10) -> str:
    """A float for people: ``precision`` significant digits, never ``0.000000`` for a small
    non-zero value."""
    if x is None:
        return "-"
    x = float(x)
    if x == 0.0:
        return "0"
    if not math.isfinite(x):
        return repr(x)
    return f"{x:.{precision}g}"


def vector(v, precision: int = 10, width: int = 17) -> str:
    return "-" if v is None else "  ".join(f"{number(x, precision):>{width}}" for x in np.asarray(v).reshape(-1))


def field_value(record: dict, name: str):
    """``record[name]``, with dots for nesting (``bounds.min``) and integers indexing lists
    (``center_of_mass.0``, ``inertia.0.1``); KeyError when absent."""
    value: Any = record
    for part in name.split("."):
        if isinstance(value, dict) and part in value:
            value = value[part]
            continue
        value = jsonable(value)
        if isinstance(value, list) and part.lstrip("-").isdigit() and -len(value) <= int(part) < len(value):
            value = value[int(part)]
            continue
        raise KeyError(name)
    return value


def field_names(record: dict) -> list[str]:
    """The names ``--field`` takes for ``record``: its keys, and the dotted names of nested keys."""
    names = []
    for key, value in record.items():
        names.append(key)
        if isinstance(value, dict):
            names += [f"{key}.{inner}" for inner in value]
    return names


def bare(value) -> str:
    """A field for shell use: numbers in full precision; a list (a vector, a matrix, names)
    space-separated, one matrix row after another (``read`` takes them apart); an object, or a
    list holding objects, as one line of JSON, which jq reads."""
    value = jsonable(value)
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, list) and not _has_object(value):
        return " ".join(bare(v) for v in value)
    if isinstance(value, (list, dict)):
        return dumps(value)
    return shown_name(str(value))   # one line, and encodable: a name's newline becomes \x0a


def _has_object(value: list) -> bool:
    """Whether a list holds an object (a dict) at any depth."""
    return any(isinstance(v, dict) or (isinstance(v, list) and _has_object(v)) for v in value)


#: Significant digits of ``--csv`` numbers by default: what a spreadsheet keeps (IEEE doubles
#: hold 15-17; 15 always round-trips a decimal, so 94.19999999999999 reads back as 94.2).
CSV_PRECISION = 15


def csv_cell(value, precision: int | None = CSV_PRECISION) -> str:
    """One CSV cell's text: floats to ``precision`` significant digits (None: full precision,
    ``repr``), booleans as true/false, None empty."""
    value = jsonable(value)
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        # Names that are not UTF-8 become ls -b escapes (stdout could not encode them);
        # newlines, tabs and carriage returns stay, inside the cell's quotes.
        return shown_name(value, keep="\n\r\t")
    if isinstance(value, float):
        if precision is None or not math.isfinite(value):
            return repr(value)
        # Rounded to ``precision`` digits, then written as the shortest text of that double
        # (so 1.0 stays "1.0", and 94.19999999999999 becomes "94.2").
        return repr(float(f"{value:.{precision}g}"))
    return str(value)


def csv_line(values, precision: int | None = None) -> str:
    """One CSV row (RFC 4180), without its line end: a cell holding a comma, a quote, a
    carriage return or a newline is quoted (so a file name with a newline stays in its row);
    floats in full precision (``repr``) unless ``precision`` digits are asked for."""
    return ",".join(_quoted(csv_cell(v, precision)) for v in values)


def _quoted(cell: str) -> str:
    # csv.writer decides on quoting by its lineterminator, so with lineterminator="" it left
    # newlines bare and split the row in two; quote by RFC 4180's rule instead.
    if any(c in cell for c in ',"\r\n'):
        return '"' + cell.replace('"', '""') + '"'
    return cell


def shown_name(name: str, keep: str = "") -> str:
    """A path as text that stays one line and stays distinguishable: bytes that are not UTF-8
    (held by Python as surrogate escapes) and control characters become ``\\xNN`` escapes, and
    a backslash becomes ``\\\\``, as ``ls -b`` writes names. Characters in ``keep`` (CSV keeps
    newlines: its quoting holds them) are left as they are."""
    if name.isprintable() and "\\" not in name:
        return name
    out = []
    for ch in name:
        code = ord(ch)
        if ch in keep:
            out.append(ch)
        elif 0xDC80 <= code <= 0xDCFF:          # surrogateescape: the undecodable byte + 0xDC00
            out.append(f"\\x{code - 0xDC00:02x}")
        elif ch == "\\":
            out.append("\\\\")
        elif not ch.isprintable() and ch != " ":
            out.append(f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}")
        else:
            out.append(ch)
    return "".join(out)


def one_line(text: str) -> str:
    """``text`` with its control characters (a file name's NUL, newline, escape) and undecodable
    bytes as ``\\xNN`` escapes: a diagnostic stays one line and cannot drive the terminal."""
    if text.isprintable():
        return text
    out = []
    for ch in text:
        code = ord(ch)
        if 0xDC80 <= code <= 0xDCFF:
            out.append(f"\\x{code - 0xDC00:02x}")
        elif code < 0x20 or code == 0x7F:
            out.append(f"\\x{code:02x}")
        else:
            out.append(ch)
    return "".join(out)


def plural(count: int, noun: str) -> str:
    """``1 face``, ``12 faces``, ``0 non-manifold vertices``."""
    if count == 1:
        return f"{count} {noun}"
    return f"{count} {noun[:-2] + 'ices' if noun.endswith('vertex') else noun + 's'}"
