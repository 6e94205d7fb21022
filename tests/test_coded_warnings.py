"""Every warning carries its code from where it is made (``p3d_cli.warning_codes``).

No code is recovered from a warning's text: each code has a case here that makes it through
the library, the results refuse a warning made without one, and the sample meshes, the
examples and the real meshes give only coded warnings.
"""

from __future__ import annotations

import ast
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import p3d_cli as p3d
from helpers.meshes import cube_triangles, write_ascii_stl, write_binary_stl
from p3d_cli.results import Bounds, BoundsResult, MeshFacts, PropsResult
from p3d_cli.warning_codes import CODES, CodedWarning, coded

REPO = Path(__file__).resolve().parent.parent
CUBE = cube_triangles()


def _stl(folder: Path, name: str, triangles, tail: bytes = b"") -> str:
    path = folder / name
    write_binary_stl(path, triangles)
    if tail:
        with open(path, "ab") as f:
            f.write(tail)
    return str(path)


def _tilted():
    return p3d.Placement(rotation=p3d.rotation_from_quaternion(0.3, 0.5, -0.7, 0.2))


def _inverted_tetrahedra():
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    return SimpleNamespace(points=points, cells=[SimpleNamespace(type="tetra", data=np.array([[0, 2, 1, 3]]))])


def _sampling(code: str):
    """``sampling_warnings`` of a run at the sample cap that missed its tolerance: no test can
    afford the 1e8 samples that make it through ``props``."""
    from p3d_cli.measure.montecarlo import MAX_SAMPLES, Estimate, sampling_warnings

    mean = np.zeros(10)
    mean[0] = 0.5
    estimate = Estimate(Bounds(np.zeros(3), np.ones(3)), MAX_SAMPLES, 1, mean, np.eye(10))
    return sampling_warnings(estimate, volume_error=0.1, tolerance=1e-9)


def _implausible(code: str):
    """``implausibilities`` of properties no solid has (a measurement that gives them warns of
    the mesh first, and then these are not added)."""
    from p3d_cli.geometry.inertia import implausibilities, mass_properties
    from p3d_cli.results import Moments

    moments = Moments(-1.0, np.zeros(3), np.diag([1.0, 1.0, 5.0]))
    return implausibilities(mass_properties(moments, density=1.0), Bounds(np.ones(3), 2 * np.ones(3)))


def cases(folder: Path) -> dict[str, object]:
    """Per code, a call that makes it: a result, or the list of warnings a measuring step makes."""
    far = _stl(folder, "far.stl", CUBE + [1e5, 0, 0])
    open_part = _stl(folder, "open.stl", CUBE[2:])
    inward = _stl(folder, "inward.stl", CUBE[:, ::-1])
    flat = _stl(folder, "flat.stl", np.zeros((2, 3, 3)) + np.eye(3)[[0, 1, 1]])
    overlap = _stl(folder, "overlap.stl", np.concatenate([CUBE, CUBE + 0.5]))
    nested = _stl(folder, "nested.stl", np.concatenate([3 * CUBE - 1, CUBE]))
    edge = _stl(folder, "edge.stl", np.concatenate([CUBE, CUBE + [1, 1, 0]]))
    trailing = _stl(folder, "trailing.stl", CUBE, tail=b"\0" * 7)
    noend = folder / "noend.stl"
    write_ascii_stl(noend, CUBE)
    noend.write_text(noend.read_text().replace("endsolid part\n", ""))
    obj = folder / "skipped.obj"
    obj.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nusemtl steel\ncurv 0 1 1 2\n"
                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    spec = folder / "box:1,2,3"
    spec.write_text("a file named like a spec\n")
    return {
        "open": lambda: p3d.props(open_part),
        "inward": lambda: p3d.props(inward),
        "flat": lambda: p3d.props(flat),
        "self-intersecting": lambda: p3d.props(overlap, intersections=True),
        "nested-shells": lambda: p3d.props(nested, intersections=True),
        "non-manifold": lambda: p3d.props(edge),
        "coarse-float32": lambda: p3d.props(far),
        "inverted-tetrahedra": lambda: p3d.props(_inverted_tetrahedra()),
        "skipped-lines": lambda: p3d.props(str(obj)),
        "trailing-data": lambda: p3d.bounds(trailing),
        "unit-slip": lambda: p3d.props("box:50,40,5", density=7850),
        "spec-shadows-file": lambda: p3d.props(str(spec.name)),
        "montecarlo-winding": lambda: p3d.props(inward, method="montecarlo", samples=2000, seed=1),
        "montecarlo-open": lambda: p3d.props(open_part, method="montecarlo", samples=2000, seed=1),
        "montecarlo-empty": lambda: p3d.props("box:1,1,1e-9", _tilted(), method="montecarlo", samples=100, seed=1),
        "montecarlo-few-inside": lambda: p3d.props("box:1,1,0.01", _tilted(), method="montecarlo", samples=20000,
                                                   seed=1),
        "montecarlo-cap": lambda: _sampling("montecarlo-cap"),
        "montecarlo-flat-box": lambda: p3d.props(flat, method="montecarlo", samples=100, seed=1),
        "implausible": lambda: _implausible("implausible"),
        "reader": lambda: p3d.props(str(noend)),
    }


def warnings_of(made) -> tuple:
    return tuple(made.warnings) if hasattr(made, "warnings") else tuple(made)


def test_the_cases_name_every_code(tmp_path):
    assert list(cases(tmp_path)) == list(CODES)


@pytest.mark.parametrize("code", list(CODES))
def test_each_code_is_given_where_its_warning_is_made(tmp_path, monkeypatch, code):
    monkeypatch.chdir(tmp_path)
    made = warnings_of(cases(tmp_path)[code]())
    assert made, f"the case for {code!r} made no warning"
    assert all(type(w) is CodedWarning and w.code in CODES for w in made), [(type(w), w) for w in made]
    assert code in [w.code for w in made]


def test_results_refuse_a_warning_without_a_code():
    facts = MeshFacts("part.stl", "stl-binary", 12, True, Bounds(np.zeros(3), np.ones(3)))
    props = p3d.props("box").properties
    with pytest.raises(TypeError, match="without a code"):
        PropsResult(facts, props, warnings=("mesh is not closed",))
    with pytest.raises(TypeError, match="without a code"):
        BoundsResult("part.stl", "stl-binary", "vertices", facts.bounds, 12, ("12 trailing bytes were ignored",))
    kept = PropsResult(facts, props, warnings=[CodedWarning("mesh is not closed", "open")])
    assert kept.warnings == ("mesh is not closed",) and kept.warning_codes == ("open",)
    with pytest.raises(TypeError):
        coded(["plain"])


def test_a_part_named_in_an_assembly_keeps_its_code_and_value(tmp_path):
    write_binary_stl(tmp_path / "far.stl", CUBE + [1e5, 0, 0])
    (tmp_path / "a.yaml").write_text("parts:\n  - name: units\n    mesh: far.stl\n")
    result = p3d.props(str(tmp_path / "a.yaml"))
    [warning] = result.warnings
    assert warning.startswith("units: coordinates are float32") and warning.code == "coarse-float32"
    assert warning.value == result.parts[0].warnings[0].value > 0


def _all_warnings(result):
    yield from result.warnings
    for part in getattr(result, "parts", ()):
        yield from _all_warnings(part)


def _coded_only(paths) -> int:
    seen = []
    for path in paths:
        for result in (p3d.props(str(path)), p3d.bounds(str(path))):
            seen += list(_all_warnings(result))
    assert all(type(w) is CodedWarning and w.code in CODES for w in seen)
    return len(seen)


def test_sample_meshes_and_examples_give_only_coded_warnings():
    _coded_only(p for p in sorted((REPO / "sample_meshes").iterdir()) if p.suffix in (".stl", ".obj", ".off", ".ply"))
    scenes = sorted((REPO / "examples").glob("*.yaml"))
    assert scenes
    for scene in scenes:
        p3d.solve_scene(p3d.load_scene(str(scene)))   # its bodies' parts are measured (a non-solid part is refused by its code)


def test_real_meshes_give_only_coded_warnings(real_meshes):
    found = _coded_only(p for p in sorted(real_meshes.iterdir()) if p.suffix.lower() in (".stl", ".obj", ".off", ".ply"))
    assert found > 0        # the real meshes hold open and inward files


def test_no_code_is_recovered_from_text():
    """The regular expressions over warning text are gone, and nothing reaches for them."""
    source = (REPO / "p3d_cli" / "warning_codes.py").read_text()
    tree = ast.parse(source)
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, (ast.Import, ast.ImportFrom))
                for alias in node.names}
    assert "re" not in imported
    names = {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    assert not {"PATTERNS", "FALLBACK"} & names
    for path in (REPO / "p3d_cli").rglob("*.py"):
        text = path.read_text(encoding="utf-8")
        assert "code_of" not in text, path
