"""The JSON Schemas of the --json records (issue 24 item 4): one per kind, valid, shipped in the
package, and enforced on every record the suite makes (tests/helpers/record_schemas.py)."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from helpers.real_meshes import REPO
from helpers import record_schemas
from p3d_cli.cli import output
from p3d_cli.cli.main import cli

jsonschema = pytest.importorskip("jsonschema")


def test_one_valid_schema_per_kind_in_the_package():
    files = sorted(p.stem for p in (REPO / "p3d_cli" / "schemas").glob("*.json"))
    assert files == sorted(output.RECORD_KINDS)
    for kind in output.RECORD_KINDS:
        schema = output.schema(kind)
        jsonschema.Draft202012Validator.check_schema(schema)
        assert schema["title"] and schema["description"]
    assert "schemas/*.json" in (REPO / "pyproject.toml").read_text()   # shipped as package data


@pytest.mark.parametrize("args, kind", [
    (["props", "box:1,2,3", "--json"], "props"),
    (["props", "sample_meshes/bracket.stl", "no-such.stl", "--json", "--jobs", "1"], "props"),
    (["bounds", "sample_meshes/bracket.stl", "--json"], "bounds"),
    (["check", "sample_meshes/bracket.stl", "--json"], "check"),
    (["solve", "examples/pendulum.yaml", "--json"], "solve"),
    (["config", "--json"], "config"),
])
def test_every_command_s_records_carry_the_version_and_validate(args, kind, monkeypatch):
    monkeypatch.chdir(REPO)
    before = record_schemas.VALIDATED[kind]
    result = CliRunner().invoke(cli, args)
    lines = result.stdout.splitlines()
    assert lines and all(json.loads(line)["schema_version"] == output.SCHEMA_VERSION for line in lines)
    assert record_schemas.VALIDATED[kind] == before + len(lines)   # the plugin checked each one


def test_a_record_that_breaks_its_schema_fails_the_test_that_made_it():
    good = output.record_line("bounds", {"source": "x", "format": "stl", "method": "vertices", "faces": 1,
                                         "min": [0, 0, 0], "max": [1, 1, 1], "size": [1, 1, 1],
                                         "center": [0.5, 0.5, 0.5], "diagonal": 1.7, "warnings": [],
                                         "warning_codes": [], "settings": None})
    assert json.loads(good)["schema_version"] == 1
    with pytest.raises(AssertionError, match="breaks p3d_cli/schemas/bounds.json: faces: -1 is less than the minimum"):
        output.record_line("bounds", {**json.loads(good), "faces": -1})
    with pytest.raises(AssertionError, match="schemas/props.json"):
        output.record_line("props", {"source": "x"})   # neither a result nor an error record
