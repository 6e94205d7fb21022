"""Packaging facts CI relies on (issue 24 items 3-4): the minimum-versions job installs exactly the
declared lower bounds, the licence file matches the declaration, and the changelog names the
current version."""

from __future__ import annotations

import re

from helpers.real_meshes import REPO

try:
    import tomllib
except ImportError:      # Python 3.10
    import tomli as tomllib

PROJECT = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]


def _bounds(requirements) -> dict[str, str]:
    out = {}
    for requirement in requirements:
        match = re.match(r"([A-Za-z0-9_.-]+)(?:\[[^\]]*\])?>=([0-9.]+)", requirement)
        if match:
            out[match.group(1).lower()] = match.group(2)
    return out


def test_the_constraints_file_pins_every_runtime_lower_bound():
    pinned = dict((name.lower(), version) for name, version in
                  re.findall(r"^([A-Za-z0-9_.-]+)==(\S+)$", (REPO / ".ci" / "constraints-min.txt").read_text(), re.M))
    declared = _bounds(PROJECT["dependencies"]) | _bounds(PROJECT["optional-dependencies"]["solve"])
    assert set(pinned) == set(declared)
    for name, bound in declared.items():
        assert pinned[name] in (bound, bound + ".0"), (name, bound, pinned[name])


def test_license_changelog_and_python_versions_agree():
    assert PROJECT["license"] == "MIT" and (REPO / "LICENSE").read_text().startswith("MIT License")
    version = re.search(r'__version__ = "([^"]+)"', (REPO / "p3d_cli" / "__init__.py").read_text()).group(1)
    assert f"## {version}" in (REPO / "CHANGELOG.md").read_text()
    declared = {c.rsplit(" ", 1)[1] for c in PROJECT["classifiers"] if re.search(r"Python :: 3\.\d+$", c)}
    assert declared == {"3.10", "3.11", "3.12", "3.13"} and PROJECT["requires-python"] == ">=3.10,<3.14"
    ci = (REPO / ".ci" / "python-versions").read_text() + (REPO / ".ci" / "min-versions").read_text()
    assert "versions=(3.12 3.13)" in ci and "3.10" in ci      # every declared version has its CI job
