"""Every --json record the suite makes is checked against its schema (issue 24 item 4).

Loaded as a pytest plugin (``conftest.py``): it wraps ``p3d_cli.cli.output.record_line``, the
one function every command prints or writes a record through, so that a record which does not
validate against ``p3d_cli/schemas/KIND.json`` fails the test that made it (in this process,
and in the forked workers of ``--jobs``, which inherit the wrapper). Counts per kind are kept,
so a test can show that the check ran.
"""

from __future__ import annotations

import json
from collections import Counter

import pytest

from p3d_cli.cli import output

#: Records validated so far in this session, by kind.
VALIDATED: Counter = Counter()
_VALIDATORS: dict = {}


def validator(kind: str):
    if kind not in _VALIDATORS:
        jsonschema = pytest.importorskip("jsonschema")
        schema = output.schema(kind)
        jsonschema.Draft202012Validator.check_schema(schema)
        _VALIDATORS[kind] = jsonschema.Draft202012Validator(schema)
    return _VALIDATORS[kind]


def validate(kind: str, line: str) -> None:
    """Raise AssertionError naming every way ``line`` breaks the schema of ``kind``."""
    record = json.loads(line)
    errors = sorted(validator(kind).iter_errors(record), key=lambda e: list(e.absolute_path))
    if errors:
        where = "; ".join(f"{'/'.join(map(str, e.absolute_path)) or '(record)'}: {e.message[:300]}" for e in errors)
        raise AssertionError(f"a {kind} record breaks p3d_cli/schemas/{kind}.json: {where}\n{line[:2000]}")
    VALIDATED[kind] += 1


_original = output.record_line


def _checked(kind: str, record: dict) -> str:
    line = _original(kind, record)
    validate(kind, line)
    return line


def pytest_configure(config):
    output.record_line = _checked


def pytest_unconfigure(config):
    output.record_line = _original
