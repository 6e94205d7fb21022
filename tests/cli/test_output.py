"""The command line's shared text helpers."""

from __future__ import annotations

from p3d_cli.cli.output import plural


def test_plural_counts_in_words():
    assert plural(1, "face") == "1 face"
    assert plural(12, "face") == "12 faces"
    assert plural(0, "non-manifold vertex") == "0 non-manifold vertices"  # was "vertexs"
    assert plural(1, "non-manifold vertex") == "1 non-manifold vertex"
    assert plural(1, "link") == "1 link"


# The one writer of records (``formatted``): every command passes its records to it.

import ast  # noqa: E402
import csv  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
from pathlib import Path  # noqa: E402

import pytest  # noqa: E402

import p3d_cli as p3d  # noqa: E402
from p3d_cli.cli import output  # noqa: E402
from p3d_cli.cli.columns import COLUMNS  # noqa: E402
from p3d_cli.errors import FieldError, UsageError  # noqa: E402

CLI = Path(output.__file__).parent
#: What only the writer (output.py, with the layouts of columns.py) may call to print a record.
WRITER_ONLY = {"csv_line", "record_line", "bare", "field_value", "dumps", "writer", "DictWriter"}


def _calls(path: Path) -> list[tuple[str, str, int]]:
    """``(owner, name, line)`` of every ``owner.name(...)`` call in a module."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and isinstance(node.func.value, ast.Name):
            out.append((node.func.value.id, node.func.attr, node.lineno))
    return out


def test_only_the_writer_serialises_records():
    """A command that wrote its own JSON, CSV row or bare field would fail here. ``output.dumps``
    stays open to the commands' text (a setting's value, a diff's old and new) but not to a
    printed record, which is checked by the records' kinds below."""
    found = []
    for path in sorted(CLI.glob("*.py")):
        if path.name in ("output.py", "columns.py"):
            continue
        for owner, name, line in _calls(path):
            if name in WRITER_ONLY and not (owner == "output" and name == "dumps"):
                found.append(f"{path.name}:{line}: {owner}.{name}")
    assert not found, found
    text = {path.name: path.read_text(encoding="utf-8") for path in CLI.glob("*.py")}
    for module, kind in (("props.py", "props"), ("bounds.py", "bounds"), ("check.py", "check"),
                         ("repair.py", "repair"), ("solve.py", "solve"), ("config.py", "config"),
                         ("diff.py", "diff"), ("reports.py", "summary"), ("robot.py", "robot"),
                         ("render.py", "render")):
        assert f'output.formatted("{kind}"' in text[module] or f'output.failed("{kind}"' in text[module], module


def test_json_is_the_library_record():
    for result in (p3d.props("box:1,2,3"), p3d.bounds("cylinder:1,1,2")):
        kind = "props" if hasattr(result, "mass") else "bounds"
        assert output.formatted(kind, result.to_dict(), "json") == result.to_json()


@pytest.mark.parametrize("kind", list(COLUMNS))
def test_csv_rows_fill_their_header_and_error_rows_keep_their_place(kind):
    header = next(csv.reader(io.StringIO(output.csv_header(kind))))
    assert header == list(COLUMNS[kind].names) and "error" in header and header[0] == "source"
    line = output.failed(kind, "a,b.stl", "a,b.stl: no such file", "csv")
    [row] = list(csv.reader(io.StringIO(line)))
    assert len(row) == len(header)
    assert row[0] == "a,b.stl" and row[header.index("error")] == "a,b.stl: no such file"


def test_csv_of_a_result_follows_the_record():
    record = p3d.props("box:1,2,3").to_dict()
    [row] = list(csv.DictReader(io.StringIO(output.csv_header("props") + "\n"
                                            + output.formatted("props", record, "csv"))))
    assert float(row["volume"]) == record["volume"] == 48.0
    assert float(row["izz"]) == pytest.approx(record["inertia"][2][2], rel=1e-14)
    assert row["warnings"] == "" and row["error"] == ""
    about = output.formatted("props", p3d.props("box:1,2,3", about=(1, 2, 3)).to_dict(), "csv", about=True)
    assert len(next(csv.reader(io.StringIO(about)))) == len(output.csv_header("props", about=True).split(","))
    sphere = p3d.props("sphere").to_dict()
    [cells] = csv.reader(io.StringIO(output.formatted("props", sphere, "csv", precision=3)))
    assert cells[0] == "sphere" and cells[5] == "4.19"      # 4/3 pi to 3 digits
    [cells] = csv.reader(io.StringIO(output.formatted("props", sphere, "csv")))
    assert cells[5] == repr(float(f"{sphere['volume']:.15g}"))


def test_fields_and_failures():
    record = p3d.bounds("box:1,2,3").to_dict()
    assert output.formatted("bounds", record, "fields", ("min", "size.2", "warnings")) == "-1.0 -2.0 -3.0\t6.0\t"
    with pytest.raises(FieldError, match="no field named 'mass'.*fields are: schema_version, source"):
        output.formatted("bounds", record, "fields", ("mass",))
    assert output.failed("props", "x.stl", "x.stl: no such file", "fields") == ""
    assert output.failed("props", "x.stl", "x.stl: no such file", "table") is None
    assert json.loads(output.failed("check", "x.stl", "bad", "json", ok=False)) == {
        "schema_version": 1, "source": "x.stl", "ok": False, "error": "bad"}
    with pytest.raises(ValueError):
        output.formatted("props", record, "yaml")


def test_two_output_formats_at_once_are_a_usage_error():
    assert output.output_style(False, False, (), "table") == "table"
    assert output.output_style(False, False, ("volume",), "table") == "fields"
    with pytest.raises(UsageError, match="choose one output format"):
        output.output_style(True, True, (), "table")
