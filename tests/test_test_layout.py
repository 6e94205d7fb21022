"""The tests' own floor plan: tests mirror the package, shared test code lives in ``helpers``.

- ``tests/<folder>/`` is a folder of ``p3d_cli`` (plus ``helpers/``, the shared test code, and
  ``fuzz/``); a test module sits at ``tests/`` top level only when its subject has no folder:
  the public facade (``p3d_cli/__init__.py``), a leaf module (``p3d_cli/errors.py``...) or the
  project itself (layout, packaging, README). Each such module is listed in ``TOP_LEVEL`` with
  its subject.
- conftest files hold fixtures (and pytest hooks) only, and no module imports ``conftest``: the
  plain functions and constants tests share are imported from ``helpers``.
- One command-line runner, ``helpers.cli.run``: no other function is a bare wrapper of click's
  ``CliRunner``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from helpers.real_meshes import REPO

TESTS = REPO / "tests"
PACKAGE = REPO / "p3d_cli"

#: Folders of tests/ that mirror no folder of the package.
OWN_FOLDERS = {"helpers", "fuzz"}

#: The test modules at tests/ top level, each with its subject: "p3d_cli" (the facade), a leaf
#: module of the package, or "project" (what the repository promises as a whole). A test of
#: anything with a folder goes in that folder.
TOP_LEVEL = {
    "test_api.py": "p3d_cli",
    "test_api_docs.py": "p3d_cli",
    "test_api_typing.py": "p3d_cli",
    "test_mesh_objects.py": "p3d_cli",
    "test_error_builtins.py": "errors",
    "test_hostile_inputs.py": "errors",
    "test_result_records.py": "results",
    "test_coded_warnings.py": "warning_codes",
    "test_schemas.py": "records",
    "test_units.py": "units",
    "test_units_convention.py": "units",
    "test_units_docs.py": "units",
    "test_layout.py": "project",
    "test_packaging.py": "project",
    "test_readme.py": "project",
    "test_test_layout.py": "project",
}

#: Files at tests/ top level that are no test module: pytest's conftest, and the user's script
#: that test_api_typing.py type-checks (data, not shared code).
TOP_LEVEL_FILES = {"conftest.py", "typed_user_script.py"}


def package_folders() -> set[str]:
    return {p.parent.name for p in PACKAGE.glob("*/__init__.py")}


def leaves() -> set[str]:
    return {p.stem for p in PACKAGE.glob("*.py")} - {"__init__", "__main__"}


def python_files() -> list[Path]:
    """Every Python module of tests/ (the fuzz corpus holds inputs, not code)."""
    return sorted(p for p in TESTS.rglob("*.py") if "corpus" not in p.relative_to(TESTS).parts)


def tree(path: Path) -> ast.Module:
    return ast.parse(path.read_text(), filename=str(path))


def relative(path: Path) -> str:
    return path.relative_to(TESTS).as_posix()


def test_the_test_folders_mirror_the_package():
    folders = {p.name for p in TESTS.iterdir() if p.is_dir() and not p.name.startswith((".", "__"))}
    strays = folders - package_folders() - OWN_FOLDERS
    assert not strays, f"tests/{sorted(strays)} mirror no folder of p3d_cli/: name each after the folder it tests"


def test_a_top_level_test_is_of_the_facade_a_leaf_or_the_project():
    subjects = leaves() | {"p3d_cli", "project"}
    for name, subject in TOP_LEVEL.items():
        assert subject in subjects, f"TOP_LEVEL[{name!r}] = {subject!r}: not the facade, a leaf or the project"
        assert subject not in package_folders(), name
    for path in sorted(TESTS.glob("*.py")):
        if path.name in TOP_LEVEL_FILES:
            continue
        assert path.name in TOP_LEVEL, (
            f"tests/{path.name} sits at tests/ top level: a test goes in the tests/ folder of the "
            f"p3d_cli/ folder it tests; shared code goes in tests/helpers/; a test of the facade, a leaf "
            f"module or the project stays here and is listed in TOP_LEVEL with its subject")


def test_conftest_is_never_imported():
    for path in python_files():
        for node in ast.walk(tree(path)):
            names = ([node.module] if isinstance(node, ast.ImportFrom) and node.level == 0 else
                     [alias.name for alias in node.names] if isinstance(node, ast.Import) else [])
            assert "conftest" not in names, (
                f"tests/{relative(path)}:{node.lineno} imports conftest: import shared code from helpers "
                f"(helpers.meshes, helpers.real_meshes...)")


def is_fixture_or_hook(node: ast.FunctionDef) -> bool:
    if node.name.startswith("pytest_"):
        return True
    for decorator in node.decorator_list:
        target = decorator.func if isinstance(decorator, ast.Call) else decorator
        if isinstance(target, ast.Attribute) and target.attr == "fixture":
            return True
    return False


@pytest.mark.parametrize("path", sorted(TESTS.rglob("conftest.py")), ids=relative)
def test_conftest_holds_fixtures_only(path):
    for node in tree(path).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            assert is_fixture_or_hook(node), (
                f"tests/{relative(path)}: {node.name} is no fixture: move it to tests/helpers/")
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            names = [t.id for t in targets if isinstance(t, ast.Name)]
            assert names == ["pytest_plugins"], (
                f"tests/{relative(path)}:{node.lineno} defines {names}: constants go in tests/helpers/")
        else:
            assert not isinstance(node, ast.ClassDef), f"tests/{relative(path)}: {node.name} goes in tests/helpers/"


def wraps_cli_runner(node: ast.FunctionDef) -> bool:
    """The function's one statement (after any docstring) returns a call made through CliRunner."""
    body = node.body[1:] if ast.get_docstring(node) is not None else node.body
    if len(body) != 1 or not isinstance(body[0], ast.Return) or body[0].value is None:
        return False
    return any(isinstance(n, ast.Name) and n.id == "CliRunner" for n in ast.walk(body[0].value))


def test_one_cli_runner():
    runner = TESTS / "helpers" / "cli.py"
    assert any(isinstance(n, ast.FunctionDef) and n.name == "run" and wraps_cli_runner(n) for n in tree(runner).body)
    for path in python_files():
        if path == runner:
            continue
        for node in ast.walk(tree(path)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                assert not wraps_cli_runner(node), (
                    f"tests/{relative(path)}:{node.lineno} {node.name} wraps CliRunner: "
                    f"use `from helpers.cli import run`")


def test_the_rules_catch_what_they_forbid(tmp_path):
    """The checks above fail on the constructs they name (so that a pass means something)."""
    wrapper = ast.parse("def run(*args):\n    return CliRunner().invoke(cli, list(args))\n").body[0]
    documented = ast.parse('def go(*a):\n    """Run."""\n    return CliRunner().invoke(cli, a)\n').body[0]
    assert wraps_cli_runner(wrapper) and wraps_cli_runner(documented)
    longer = ast.parse("def go(*a):\n    r = CliRunner().invoke(cli, a)\n    return r.output\n").body[0]
    assert not wraps_cli_runner(longer)
    fixture = ast.parse("@pytest.fixture(scope='session')\ndef cube():\n    return 1\n").body[0]
    plain = ast.parse("def cube_triangles():\n    return 1\n").body[0]
    assert is_fixture_or_hook(fixture) and not is_fixture_or_hook(plain)
    assert "measure" in package_folders() and "errors" in leaves() and "measure" not in leaves()
