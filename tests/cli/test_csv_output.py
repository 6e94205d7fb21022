"""``--csv`` a spreadsheet wants: bounds, principal moments, --about, --precision, zeros that are
zero, warning codes, RFC 4180 quoting and names that are not UTF-8."""

from __future__ import annotations

import csv
import io
import json
import os

import pytest

from helpers.cli import run
from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl


def rows(text: str) -> list[dict]:
    return list(csv.DictReader(io.StringIO(text)))


@pytest.fixture
def noisy(tmp_path):
    """An axis-aligned 1.1 x 2.2 x 0.3 box at (0.1, 0.2, 0.3): its products of inertia are exactly 0,
    but the float64 sums leave ~1e-18 (within their rounding bounds) and a volume 0.7260000000000001."""
    path = tmp_path / "box.stl"
    write_ascii_stl(path, cube_triangles() * [1.1, 2.2, 0.3] + [0.1, 0.2, 0.3])
    return path


def test_bounds_principal_moments_and_about_columns(noisy):
    record = json.loads(run("props", noisy, "--json", "--about", "1,2,3").stdout)
    [row] = rows(run("props", noisy, "--csv", "--about", "1,2,3", "--precision", "17").stdout)
    for axis, i in zip("xyz", range(3)):
        assert float(row[f"min_{axis}"]) == record["bounds"]["min"][i]
        assert float(row[f"max_{axis}"]) == record["bounds"]["max"][i]
        assert float(row[f"about_{axis}"]) == [1.0, 2.0, 3.0][i]
    assert [float(row[k]) for k in ("i1", "i2", "i3")] == pytest.approx(record["principal_moments"], rel=1e-15)
    assert float(row["about_ixx"]) == pytest.approx(record["inertia_about"][0][0], rel=1e-15)
    assert float(row["about_iyz"]) == pytest.approx(record["inertia_about"][1][2], rel=1e-15)
    assert "about_x" not in rows(run("props", noisy, "--csv").stdout)[0]


def test_values_within_their_rounding_bound_print_as_zero(noisy):
    record = json.loads(run("props", noisy, "--json").stdout)
    ixy, bound = record["inertia"][0][1], record["uncertainty"]["inertia"][0][1]
    assert ixy != 0 and abs(ixy) <= bound          # the premise: noise, within its bound
    [row] = rows(run("props", noisy, "--csv").stdout)
    assert (row["ixy"], row["ixz"], row["iyz"]) == ("0.0", "0.0", "0.0")
    assert row["volume"] == "0.726"                # 15 significant digits by default
    table = run("props", noisy).stdout
    assert "e-1" not in table                      # no 1e-18 noise in the table
    assert float(row["ixx"]) == pytest.approx(record["inertia"][0][0], rel=1e-14)


def test_precision_counts_significant_digits(noisy):
    [row] = rows(run("props", noisy, "--csv", "--precision", "3").stdout)
    assert row["ixx"] == repr(float(f"{json.loads(run('props', noisy, '--json').stdout)['inertia'][0][0]:.3g}"))
    assert "volume            0.726\n" in run("props", noisy, "--precision", "3").stdout


def test_warnings_column_holds_codes(tmp_path):
    path = tmp_path / "open.stl"
    write_binary_stl(path, cube_triangles()[2:])
    [row] = rows(run("props", path, "--csv").stdout)
    assert row["warnings"] == "open"
    [row] = rows(run("bounds", path, "--csv").stdout)
    assert row["warnings"] == ""


@pytest.mark.parametrize("command", ["props", "bounds", "check"])
def test_a_newline_in_a_name_stays_in_its_row(tmp_path, command):
    path = tmp_path / 'odd "name",\nwith newline.stl'
    write_binary_stl(path, cube_triangles())
    result = run(command, path, tmp_path / "missing\n.stl", "--csv")
    parsed = rows(result.stdout)
    assert [r["source"] for r in parsed] == [str(path), str(tmp_path / "missing\n.stl")]
    assert parsed[1]["error"]


def test_names_that_are_not_utf8_are_escaped_and_json_round_trips(tmp_path):
    raw = os.fsencode(tmp_path) + b"/caf\xe9.stl"
    with open(raw, "wb"):
        pass
    write_binary_stl(os.fsdecode(raw), cube_triangles())
    name = os.fsdecode(raw)
    [row] = rows(run("props", name, "--csv").stdout)
    assert row["source"] == str(tmp_path) + "/caf\\xe9.stl"
    record = json.loads(run("props", name, "--json").stdout)
    assert os.fsencode(record["source"]) == raw
    assert run("props", name).stdout.startswith(str(tmp_path) + "/caf\\xe9.stl\n")
