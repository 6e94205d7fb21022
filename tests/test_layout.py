"""The floor plan: no import cycle, small modules, click only in the command line."""

from __future__ import annotations

import ast

from conftest import REPO

PACKAGE = REPO / "p3d_cli"
MAX_LINES = 450


def modules() -> dict[str, ast.Module]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        parts = path.relative_to(REPO).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = ast.parse(path.read_text(), str(path))
    return out


def imports(name: str, tree: ast.Module, known: set[str]) -> set[str]:
    """The p3d_cli modules ``name`` imports (anywhere in it, deferred imports included; the
    type-checking block of the package's face is not imported at run time). A package whose
    module is imported is not counted: Python runs its ``__init__`` first, before the importer."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and getattr(node.test, "id", None) == "TYPE_CHECKING":
            node.body = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # ``from pkg import mod`` imports the module pkg.mod; ``from mod import name`` imports mod.
            subs = {f"{node.module}.{a.name}" for a in node.names} & known
            names_only = any(f"{node.module}.{a.name}" not in known for a in node.names)
            found |= subs | ({node.module} if names_only else set())
    return {m for m in found if m in known and m != name}


def test_no_import_cycles():
    trees = modules()
    graph = {name: imports(name, tree, set(trees)) for name, tree in trees.items()}
    # The package's face imports its names lazily (importlib), so it is no node of a cycle.
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                cycle = stack[stack.index(nxt):] + [nxt]
                raise AssertionError("import cycle: " + " -> ".join(cycle))
            if nxt not in state:
                visit(nxt)
        stack.pop()
        state[node] = 2

    for name in sorted(graph):
        if name not in state:
            visit(name)


def test_modules_stay_small():
    big = {str(p.relative_to(REPO)): n for p in PACKAGE.rglob("*.py")
           if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not big, f"modules over {MAX_LINES} lines: {big}"


def test_click_only_in_the_command_line():
    trees = modules()
    users = {name for name, tree in trees.items()
             if any(isinstance(n, (ast.Import, ast.ImportFrom)) and "click" in
                    ([a.name.split(".")[0] for a in n.names] if isinstance(n, ast.Import)
                     else [(n.module or "").split(".")[0]])
                    for n in ast.walk(tree))}
    assert users and all(name.startswith("p3d_cli.cli") for name in users), users


def test_the_package_ships_its_type_information():
    assert (PACKAGE / "py.typed").is_file()
