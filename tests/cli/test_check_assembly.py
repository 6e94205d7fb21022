"""``p3d check`` reads the assembly files ``props`` and ``bounds`` accept (issue 24, item 2):
each mesh part checked on its own, nested assemblies too, one verdict for the whole."""

from __future__ import annotations

import json


from helpers.cli import run
from helpers.meshes import cube_triangles, write_binary_stl

CUBE = cube_triangles()


def _assembly(tmp_path):
    write_binary_stl(tmp_path / "good.stl", CUBE)
    write_binary_stl(tmp_path / "open.stl", CUBE[2:])
    (tmp_path / "inner.yaml").write_text("units: mm\nparts:\n  - name: lid\n    mesh: open.stl\n"
                                         "  - name: peg\n    shape: cylinder:1,1,2\n")
    (tmp_path / "link.yaml").write_text("units: mm\nparts:\n  - name: base\n    mesh: good.stl\n"
                                        "    scale: [-1, 1, 1]\n"
                                        "  - name: cover\n    assembly: inner.yaml\n    translate: [0, 0, 5]\n")
    return tmp_path / "link.yaml"


def test_check_accepts_what_props_and_bounds_accept(tmp_path):
    link = _assembly(tmp_path)
    assert run("props", link).exit_code == 0 and run("bounds", link).exit_code == 0
    result = run("check", link, "--json")
    assert result.exit_code == 1, result.output       # the nested part is open: a verdict, not exit 2
    record = json.loads(result.stdout)
    assert record["format"] == "assembly" and record["ok"] is False
    assert "cover/lid:closed" in record["failed"] and not any(f.startswith("base:") for f in record["failed"])
    assert [part["name"] for part in record["parts"]] == ["base", "cover/lid"]
    assert record["faces"] == 12 + 10 and record["boundary_edges"] == record["parts"][1]["boundary_edges"] > 0


def test_a_clean_assembly_passes_and_limits_apply_to_the_whole(tmp_path):
    _assembly(tmp_path)
    (tmp_path / "clean.yaml").write_text("parts:\n  - mesh: good.stl\n  - mesh: good.stl\n    translate: [3, 0, 0]\n"
                                         "  - shape: box:1,1,1\n")
    assert run("check", tmp_path / "clean.yaml").exit_code == 0
    result = run("check", tmp_path / "clean.yaml", "--max-faces", "20", "--json")
    assert result.exit_code == 1 and json.loads(result.stdout)["failed"] == ["max-faces"]


def test_an_unreadable_part_names_the_part(tmp_path):
    (tmp_path / "bad.yaml").write_text("parts:\n  - mesh: missing.stl\n")
    result = run("check", tmp_path / "bad.yaml")
    assert result.exit_code == 2 and "bad.yaml: parts[0]" in result.stderr and "Traceback" not in result.output
