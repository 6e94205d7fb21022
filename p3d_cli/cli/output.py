"""The one writer of records: ``formatted`` prints a record the library built as ``--json``,
``--csv`` (its layout in ``p3d_cli.cli.columns``) or ``--field``, and ``failed`` the record of
an input that could not be done; plus numbers and vectors for people. Each command's
human-readable text lives with the command."""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from p3d_cli.cli.columns import COLUMNS, CSV_PRECISION
from p3d_cli.errors import FieldError

# The JSON writer is the library's (``to_json`` of every result); this module adds the record's kind.
from p3d_cli.records import SCHEMA_VERSION, dumps, jsonable  # noqa: F401 (used by every command)

#: The output styles ``formatted`` writes (a command's default text is its own).
STYLES = ("json", "csv", "fields")


#: The kinds of record, each with its schema file.
RECORD_KINDS = ("props", "bounds", "check", "diff", "solve", "summary", "config", "repair")

#: Kinds of ``--json`` line written without ``schema_version`` and without a schema file
#: (``p3d robot check``'s link records, ``p3d render``'s line): kept as they were printed.
UNVERSIONED = ("robot", "render")


def record_line(kind: str, record: dict) -> str:
    """One ``--json`` record of ``kind`` (``RECORD_KINDS``) as a line of JSON, with its
    ``schema_version`` first. Every record p3d prints or writes goes through here."""
    return dumps({"schema_version": SCHEMA_VERSION, **{k: v for k, v in record.items() if k != "schema_version"}})


def formatted(kind: str, record: dict, style: str, fields: tuple[str, ...] = (), precision: int | None = None,
              about: bool = False) -> str:
    """One record of ``kind`` in ``style``: the one writer of every command's records.

    Parameters
    ----------
    kind : str
        One of ``RECORD_KINDS`` or ``UNVERSIONED`` (``--csv``: one of ``p3d_cli.cli.columns.COLUMNS``).
    record : dict
        The record as the library builds it (``props_record``, ``check_record``, ...), with
        the command's additions (``settings``).
    style : str
        ``json`` (one line of JSON, ``schema_version`` first), ``csv`` (its rows, in the
        kind's columns) or ``fields`` (the values of ``fields``, tab-separated, for the shell).
    fields : tuple of str
        ``--field`` names: dots for nesting, integers for list items.
    precision : int, optional
        ``--csv``: significant digits of floats (default: the kind's, ``CSV_PRECISION``).
    about : bool
        ``--csv``: with the ``--about`` columns.

    Raises
    ------
    FieldError
        A name in ``fields`` that the record does not have.
    """
    if style == "json":
        return dumps(record) if kind in UNVERSIONED else record_line(kind, record)
    if style == "csv":
        columns = COLUMNS[kind]
        digits = precision or columns.precision
        return "\n".join(csv_line(columns.row(row, about), digits) for row in columns.rows(record))
    if style == "fields":
        return "\t".join(bare(field(record, name)) for name in fields)
    raise ValueError(f"no output style {style!r}; styles are: " + ", ".join(STYLES))


def failed(kind: str, source: str, message: str, style: str, about: bool = False, **extra) -> str | None:
    """The record of an input that could not be done (``source``, ``extra``, ``error``) in
    ``style``: an empty line for ``fields`` (so that lines stay aligned with inputs), nothing
    for any style but ``STYLES`` (the command's text: the error goes to stderr)."""
    if style == "fields":
        return ""
    if style not in STYLES:
        return None
    return formatted(kind, {"source": source, **extra, "error": message}, style, about=about)


def csv_header(kind: str, about: bool = False) -> str:
    """The ``--csv`` header line of ``kind``."""
    return csv_line(COLUMNS[kind].header(about))


def field(record: dict, name: str):
    """``record``'s field ``name`` (dots for nesting, integers for list items).

    Raises
    ------
    FieldError
        No such field (the message lists the record's fields).
    """
    try:
        return field_value(record, name)
    except KeyError:
        raise FieldError("--field", f"no field named {name!r}",
                         "fields are: " + ", ".join(field_names(record))) from None


def output_style(as_json: bool, as_csv: bool, fields, default: str) -> str:
    """``csv``, ``fields``, ``json`` or ``default`` (the command's text); two at once is a usage error."""
    from p3d_cli.errors import UsageError

    given = [flag for flag, on in (("--json", as_json), ("--csv", as_csv), ("--field", bool(fields))) if on]
    if len(given) > 1:
        raise UsageError("/".join(given), "both given", "choose one output format")
    return "csv" if as_csv else "fields" if fields else "json" if as_json else default


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
