"""The floor plan (docs/architecture.md): folders that say their role, one road down the floors.

Read from the code itself with ``ast``: every import of a ``p3d_cli`` module, at the top of a
module or inside a function, except inside the callbacks named below.
"""

from __future__ import annotations

import ast
import functools
import re
from pathlib import Path

import pytest

from helpers.real_meshes import REPO

PACKAGE = REPO / "p3d_cli"
MAX_LINES = 450

#: The modules left loose at the top of the package: the leaves everyone imports, the package's
#: face and ``python -m p3d_cli``.
LEAVES = {"errors", "records", "results", "units", "warning_codes"}
LOOSE = LEAVES | {"__init__", "__main__"}

#: Each folder's floor: a module may import from its own floor and the floors below, never above.
FLOORS = {
    "cli": 5,
    "robots": 4, "constraints": 4, "render": 4, "batch": 4, "repairs": 4,
    "measure": 3,
    "mesh": 2, "io": 2, "shapes": 2,
    "geometry": 1,
    **{leaf: 0 for leaf in LEAVES},
}
#: Folders of data, no code.
DATA = {"schemas"}

#: Functions that are callbacks, by name: Jupyter calls a value's display methods
#: (``_repr_html_``, ``_repr_png_``...); they are no part of the road from an input to a result,
#: so what they import may stand on any floor.
CALLBACK = re.compile(r"^_repr_[a-z]+_$")

#: Imports from a higher floor that stand today, each with its reason. Keep it short: a new
#: entry needs the lead's word.
KNOWN_CLIMBS: set[tuple[str, str]] = set()


def module_name(path: Path) -> str:
    parts = path.relative_to(REPO).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@functools.lru_cache(maxsize=None)
def modules(package: Path = PACKAGE) -> dict[str, ast.Module]:
    """Every module's syntax tree, parsed once per package (the tests only read them)."""
    root = package.parent
    out = {}
    for path in package.rglob("*.py"):
        parts = path.relative_to(root).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = ast.parse(path.read_text(), str(path))
    return out


def _import_nodes(tree: ast.Module):
    """Every import node of ``tree``, with the function it stands in (None at module level);
    the type-checking block of a face is not imported at run time, so it is left out."""
    def walk(node, function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and getattr(child.test, "id", None) == "TYPE_CHECKING":
                continue
            if isinstance(child, (ast.Import, ast.ImportFrom)):
                yield child, function
            inner = child.name if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef)) else function
            yield from walk(child, inner)
    yield from walk(tree, None)


def imports(name: str, tree: ast.Module, known: set[str], callbacks: bool = False) -> dict[str, int]:
    """The p3d_cli modules ``name`` imports, each with the line of its first import (callbacks'
    imports only when ``callbacks``). ``from pkg import mod`` imports the module ``pkg.mod``;
    ``from mod import name`` imports ``mod``."""
    found: dict[str, int] = {}
    for node, function in _import_nodes(tree):
        if function and CALLBACK.match(function) and not callbacks:
            continue
        if isinstance(node, ast.Import):
            targets = {a.name for a in node.names}
        elif node.module and node.level == 0:
            subs = {f"{node.module}.{a.name}" for a in node.names} & known
            names_only = any(f"{node.module}.{a.name}" not in known for a in node.names)
            targets = subs | ({node.module} if names_only else set())
        else:
            targets = set()
        for target in targets:
            if target in known and target != name:
                found.setdefault(target, node.lineno)
    return found


@functools.lru_cache(maxsize=None)
def import_graph(package: Path = PACKAGE) -> dict[str, dict[str, int]]:
    trees = modules(package)
    return {name: imports(name, tree, set(trees)) for name, tree in trees.items()}


def find_cycle(graph: dict[str, dict[str, int]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for name in sorted(graph):
        if name not in state and (cycle := visit(name)):
            return cycle
    return None


def room(name: str) -> str:
    """The folder (or loose module) of ``p3d_cli.x.y``: ``x``; the package's face is ``""``."""
    parts = name.split(".")
    return parts[1] if len(parts) > 1 else ""


def climbs(graph: dict[str, dict[str, int]]) -> list[str]:
    """Every import from a lower floor to a higher one, as ``module:line -> module``."""
    out = []
    for name, targets in sorted(graph.items()):
        here = room(name)
        if here in ("", "__main__"):          # the face and ``python -m`` stand above everything
            continue
        for target, line in sorted(targets.items()):
            there = room(target)
            if there == "":
                continue                      # the face's own names (``__version__``): checked below
            if FLOORS[there] > FLOORS[here] and (name, target) not in KNOWN_CLIMBS:
                out.append(f"{name}:{line} -> {target}")
    return out


def test_no_import_cycles():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_the_top_holds_roles_and_leaves_only():
    loose = {p.stem for p in PACKAGE.glob("*.py")} - LOOSE
    assert not loose, f"loose modules at the top of p3d_cli: {sorted(loose)}; put each in the folder of its role"
    folders = {p.name for p in PACKAGE.iterdir() if p.is_dir() and p.name != "__pycache__"}
    unknown = folders - set(FLOORS) - DATA
    assert not unknown, f"folders with no floor: {sorted(unknown)}; give them one in FLOORS and docs/architecture.md"
    assert LEAVES <= {p.stem for p in PACKAGE.glob("*.py")}


def test_no_import_climbs_to_a_higher_floor():
    assert climbs(import_graph()) == []


def test_known_climbs_still_stand():
    """An entry of ``KNOWN_CLIMBS`` that the code no longer has is removed, not kept."""
    graph = import_graph()
    gone = [pair for pair in KNOWN_CLIMBS if pair[1] not in graph.get(pair[0], {})]
    assert not gone, f"remove these from KNOWN_CLIMBS: {gone}"


def test_outside_measure_only_its_face_is_called():
    """Scenes, robots, pictures and commands call ``p3d_cli.measure``'s names, not its modules."""
    inside = [f"{name}:{line} -> {target}" for name, targets in sorted(import_graph().items())
              if room(name) not in ("measure", "")
              for target, line in sorted(targets.items())
              if target.startswith("p3d_cli.measure.")]
    assert inside == []


#: The one module that calls the package's face: the display callbacks' pictures are drawn
#: through the public API, as a user draws them (``p3d_cli.render.notebook``).
FACE_USERS = {"p3d_cli.render.notebook"}


def test_the_face_is_imported_for_its_version_only():
    users = []
    for name, tree in modules().items():
        if name == "p3d_cli" or name in FACE_USERS:
            continue
        for node, _ in _import_nodes(tree):
            if isinstance(node, ast.Import) and any(a.name == "p3d_cli" for a in node.names):
                users.append(f"{name}:{node.lineno}")
            if isinstance(node, ast.ImportFrom) and node.module == "p3d_cli" and node.level == 0:
                names = {a.name for a in node.names}
                if not names <= LOOSE | set(FLOORS) | {"__version__"}:
                    users.append(f"{name}:{node.lineno}")
    assert users == [], "the library's modules import each other, not the package's face"


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


# The checks themselves, on small packages written for the purpose: each must be able to fail.

def _package(tmp_path: Path, files: dict[str, str]) -> Path:
    for rel, text in files.items():
        path = tmp_path / "p3d_cli" / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    return tmp_path / "p3d_cli"


def _graph(package: Path) -> dict[str, dict[str, int]]:
    trees = modules(package)
    return {name: imports(name, tree, set(trees)) for name, tree in trees.items()}


def test_a_cycle_is_found(tmp_path):
    package = _package(tmp_path, {"__init__.py": "", "mesh/__init__.py": "", "mesh/a.py": "import p3d_cli.mesh.b\n",
                                  "mesh/b.py": "def f():\n    from p3d_cli.mesh import a\n"})
    assert find_cycle(_graph(package)) == ["p3d_cli.mesh.a", "p3d_cli.mesh.b", "p3d_cli.mesh.a"]


@pytest.mark.parametrize("callback, found", [("def later():", True), ("def _repr_html_(self):", False)])
def test_a_climb_is_found_even_deferred_but_not_in_a_callback(tmp_path, callback, found):
    package = _package(tmp_path, {"__init__.py": "", "geometry/__init__.py": "", "measure/__init__.py": "",
                                  "measure/exact.py": "",
                                  "geometry/rotation.py": f"{callback}\n    from p3d_cli.measure import exact\n"})
    assert climbs(_graph(package)) == (["p3d_cli.geometry.rotation:2 -> p3d_cli.measure.exact"] if found else [])


def test_every_shape_and_constraint_type_is_public():
    """A shape class in the registry is a public name (``p3d.Capsule`` was missing once), and
    every constraint type the registry names is one the public scene reader takes."""
    import p3d_cli
    from p3d_cli.constraints.registry import CONSTRAINT_TYPES
    from p3d_cli.constraints.scene import parse_scene
    from p3d_cli.shapes import SHAPES

    missing = sorted(cls.__name__ for cls in SHAPES.values() if cls.__name__ not in p3d_cli.__all__)
    assert not missing, f"shapes missing from p3d_cli.__all__: {missing}"
    assert all(getattr(p3d_cli, cls.__name__) is cls for cls in SHAPES.values())
    assert "parse_scene" in p3d_cli.__all__
    for kind in CONSTRAINT_TYPES:
        entry = {"type": kind, "a": "a", "b": "b", "attach_a": [0, 0, 0]}
        if kind == "bar":
            entry["attach_b"] = [0, 0, 1]
        if kind == "hinge":
            entry["axis_a"] = [0, 0, 1]
        body = {"mass": 1.0, "inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}
        scene = parse_scene({"bodies": {"a": dict(body), "b": {**body, "position": [0, 0, 2]}},
                             "constraints": [entry]}, "scene.yaml", ".")
        assert [type(c).__name__ for c in scene.constraints] and len(scene.constraints) == 1
