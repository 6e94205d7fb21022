"""The ``--json`` record of every result: one JSON writer, and the ``to_dict()`` and ``to_json()``
every result class has (``Record``), so that a Python user gets the very record the command
line prints. The record of each kind is built beside its result class; ``p3d_cli.cli.output``
writes the command line's through the same ``dumps``."""

from __future__ import annotations

import json
import math
import re
from typing import Any, ClassVar

import numpy as np

#: The layout version of every --json record (``schema_version``); the schemas of each kind of
#: record are the package's ``p3d_cli/schemas/KIND.json`` (JSON Schema, draft 2020-12).
SCHEMA_VERSION = 1


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


def dumps(record: object) -> str:
    """One line of JSON; floats keep full precision (Python's repr round-trips float64).

    A path's bytes that are not UTF-8 (held by Python as surrogate escapes, ``U+DC80``-
    ``U+DCFF``) are written as ``\\udcNN`` escapes: valid JSON that Python's ``json.loads``
    and ``os.fsencode`` turn back into the original bytes."""
    value = jsonable(record)
    try:
        text = json.dumps(value, ensure_ascii=False, allow_nan=False)
    except ValueError:
        raise _not_finite(value) from None
    return _SURROGATE.sub(lambda m: f"\\u{ord(m.group(0)):04x}", text)


def _not_finite(value):
    """The error for a record holding a number JSON cannot write (``inf``, ``nan``): the
    computation overflowed float64. Named by the record's source and the first such field."""
    from p3d_cli.errors import RangeError

    def first(v, path: str) -> str | None:
        if isinstance(v, float) and not math.isfinite(v):
            return path
        items = v.items() if isinstance(v, dict) else enumerate(v) if isinstance(v, list) else ()
        for key, inner in items:
            found = first(inner, f"{path}.{key}" if path else str(key))
            if found is not None:
                return found
        return None

    source = value.get("source", "") if isinstance(value, dict) else ""
    return RangeError(str(source), f"{first(value, '') or 'a result'} is not a finite number (float64 overflowed: the "
                      "coordinates or the placement are too large to compute with)",
                      "scale the input down (--scale, or --units with a larger unit) or check its coordinates")


_SURROGATE = re.compile("[\ud800-\udfff]")


class Record:
    """What every result gives a Python user: its ``--json`` record, as plain values and as text."""

    #: Whether the command line's record has ``settings`` (the project settings it applied).
    _has_settings: ClassVar[bool] = True

    def _record(self) -> dict[str, Any]:
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The record ``--json`` prints, as plain Python values (``json.dumps`` takes it):
        ``schema_version`` first, arrays as lists; ``settings`` (the project settings the
        command line applied) is None."""
        record = {"schema_version": SCHEMA_VERSION, **self._record()}
        if self._has_settings:
            record["settings"] = None
        return jsonable(record)

    def to_json(self) -> str:
        """The line ``--json`` prints (without its newline): ``to_dict()`` as one line of JSON.

        Raises
        ------
        RangeError
            A value is not finite (float64 overflowed), which JSON cannot write."""
        return dumps(self.to_dict())
