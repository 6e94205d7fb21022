"""docs/units.md and docs/assemblies.md cannot drift: their `$ p3d ...` examples run as shown
(the assembly file of docs/assemblies.md is written from its YAML block first)."""

from __future__ import annotations

import re

import pytest

from helpers.real_meshes import REPO
from helpers.doc_examples import assert_as_shown
from helpers.doc_examples import examples as doc_examples

DOCS = {name: (REPO / "docs" / name).read_text() for name in ("units.md", "assemblies.md")}


def examples():
    return [(name, line, shown) for name, doc in DOCS.items() for line, shown in doc_examples(doc)]


@pytest.mark.parametrize("doc, line, shown", examples(), ids=lambda v: v if isinstance(v, str) else "")
def test_examples_run_as_shown(tmp_path, doc, line, shown):
    yaml_block = re.search(r"```yaml\n(.*?)```", DOCS["assemblies.md"], re.S).group(1)
    (tmp_path / "link.yaml").write_text(yaml_block)
    assert_as_shown(line, shown, tmp_path)


def test_python_example_runs():
    code = re.search(r"```python\n(.*?)```", DOCS["units.md"], re.S).group(1)
    scope: dict = {}
    exec(code, scope)                      # noqa: S102 - the document's own example
    assert scope["r"].units["mass"] == "kg"
    assert len(examples()) >= 5
