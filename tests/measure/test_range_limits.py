"""Numbers at the edges of float64: huge coordinates and placements give a right number or one
clear error (exit 2), never an internal error, ``nan`` or ``inf`` (issue 27's numeric cases)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from helpers.cli import run
import p3d_cli as p3d

CUBE = p3d.parse_shape("box:1,1,1").triangles()


def write_obj(path, triangles) -> str:
    """An OBJ of ``triangles`` (one vertex per corner), coordinates as shortest round-trip text."""
    v = np.asarray(triangles, dtype=np.float64).reshape(-1, 3)
    lines = ["v %r %r %r" % tuple(p) for p in v.tolist()]
    lines += ["f %d %d %d" % (3 * i + 1, 3 * i + 2, 3 * i + 3) for i in range(len(v) // 3)]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def one_error_line(result) -> str:
    assert result.exit_code == 2, (result.exit_code, result.output)
    assert "internal error" not in result.output and "Traceback" not in result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("p3d: error: ")
    return lines[0]


@pytest.mark.parametrize("scale", [1e154, 1e200, 1e300])
def test_bounds_of_parts_past_1e154_are_numbers(tmp_path, scale):
    # The diagonal's squares overflow past 1.34e154; the diagonal itself does not.
    path = write_obj(tmp_path / "big.obj", CUBE * scale)
    result = run("bounds", "--json", path)
    assert result.exit_code == 0, result.output
    record = json.loads(result.stdout)
    assert record["diagonal"] == pytest.approx(2 * math.sqrt(3) * scale, rel=1e-15)
    assert record["center"] == [0.0, 0.0, 0.0]
    assert result.stderr == ""                                    # no numpy overflow warnings


def test_bounds_translated_to_1e308_keep_their_centre(tmp_path):
    result = run("bounds", "--json", "--translate", "1e308,0,0", write_obj(tmp_path / "c.obj", CUBE))
    assert result.exit_code == 0, result.output
    record = json.loads(result.stdout)
    assert record["center"] == [1e308, 0.0, 0.0] and record["min"][0] == 1e308


@pytest.mark.parametrize("args", [["--translate", "1.7e308,0,0", "--scale", "1e308"],
                                  ["--translate", "1e308,0,0", "--scale", "1e308"],
                                  ["--scale", "1e308"]])
@pytest.mark.parametrize("thing", ["mesh", "sphere:1"])
def test_bounds_beyond_float64_are_one_clear_error(tmp_path, args, thing):
    # A corner past 1.8e308, or a size of 2e308: inf in the text, an internal error in JSON.
    source = write_obj(tmp_path / "c.obj", CUBE) if thing == "mesh" else thing
    assert "overflow float64" in one_error_line(run("bounds", *args, source))
    result = run("bounds", "--json", *args, source)
    one_error_line(result)
    assert "overflow float64" in json.loads(result.stdout)["error"]


@pytest.mark.parametrize("offset", [0.0, 3e200])
def test_check_of_an_obj_with_1e200_coordinates_is_one_clear_error(tmp_path, offset):
    # Its volume (8e600) is beyond float64: it was reported as 0 ("not outward"), or nan, or
    # broke --json with an internal error.
    path = write_obj(tmp_path / "big.obj", CUBE * 1e200 + offset)
    for args in (["check", path], ["check", "--json", path], ["props", path], ["props", "--json", path]):
        line = one_error_line(run(*args))
        assert "overflow" in line and "float64" in line


def test_check_below_the_overflow_keeps_its_volume(tmp_path):
    path = write_obj(tmp_path / "large.obj", CUBE * 1e100)
    record = json.loads(run("check", "--json", path).stdout)
    assert record["volume"] == pytest.approx(8e300, rel=1e-14) and record["ok"]
