"""The public Python API: ``import p3d_cli as p3d`` gives what the command line computes."""

from __future__ import annotations

import json
import pickle
import subprocess
import sys

import numpy as np
import pytest
from click.testing import CliRunner

import p3d_cli as p3d
from p3d_cli import errors
from p3d_cli.cli.main import cli
from p3d_cli.cli.props import props_record
from p3d_cli.cli.output import jsonable

from helpers.real_meshes import REPO

CUBE_V = np.array([[x, y, z] for x in (0.0, 2.0) for y in (0.0, 3.0) for z in (0.0, 5.0)]) + [10.0, -4.0, 1.5]
# Outward triangles of the box above (vertex i has bits x=4, y=2, z=1).
CUBE_F = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                   [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


def cli_json(*args, stdin=None) -> dict:
    result = CliRunner().invoke(cli, ["props", *args, "--json"], input=stdin)
    assert result.exit_code == 0, result.output
    record = json.loads(result.stdout)
    # what the command line adds to the library's record: the record's version, the settings used
    assert record.pop("schema_version") == 1 and record.pop("settings") is None
    return record


def comparable(record: dict) -> dict:
    """The numbers of a record (source and format say how the input was given, not what it is)."""
    keys = ("volume", "mass", "density", "center_of_mass", "inertia", "inertia_origin",
            "principal_moments", "principal_axes", "second_moments", "bounds", "closed", "faces")
    return {k: record[k] for k in keys}


def test_props_of_a_path_a_spec_and_a_shape_equal_the_command_line():
    path = str(REPO / "sample_meshes" / "bracket.stl")
    assert jsonable(props_record(p3d.props(path, density=7.85))) == cli_json(path, "--density", "7.85")
    spec = "cylinder:0.5,0.5,2"
    from_cli = cli_json(spec, "--rotate", "x:90")
    placement = p3d.Placement(rotation=p3d.rotation_from_axis_degrees("x", 90))
    assert jsonable(props_record(p3d.props(spec, placement))) == from_cli
    shape = p3d.Cylinder(0.5, 2.0)
    assert comparable(jsonable(props_record(p3d.props(shape, placement)))) == comparable(from_cli)


def test_props_of_arrays_equal_the_same_triangles_from_a_file(tmp_path):
    triangles = CUBE_V[CUBE_F]
    path = tmp_path / "box.stl"
    _write_ascii_stl(path, triangles)
    from_cli = comparable(cli_json(str(path)))
    for thing in (triangles, (CUBE_V, CUBE_F), triangles.tolist(), (CUBE_V.tolist(), CUBE_F.tolist())):
        result = p3d.props(thing)
        assert result.facts.source == "<array>"
        assert comparable(jsonable(props_record(result))) == from_cli
    assert p3d.props(triangles).properties.volume == pytest.approx(30.0, rel=1e-15)


def test_loaded_meshes_and_paths_are_the_same_road(tmp_path):
    path = str(REPO / "sample_meshes" / "bracket.obj")
    mesh = p3d.load_mesh(path)
    assert mesh.where == path
    a, b = p3d.props(mesh), p3d.props(path)
    assert a.properties.inertia.tolist() == b.properties.inertia.tolist()
    assert p3d.bounds(mesh).bounds.max.tolist() == p3d.bounds(path).bounds.max.tolist()
    assert p3d.check(mesh).ok == p3d.check(path).ok


def test_parse_shape_and_the_shape_classes():
    assert p3d.parse_shape("box:1,2,3") == p3d.Box(1.0, 2.0, 3.0)
    assert p3d.parse_shape("sphere:0.5") == p3d.Sphere(0.5)
    with pytest.raises(p3d.SpecError, match="no shape named 'cube'"):
        p3d.parse_shape("cube:1,2,3")
    assert p3d.props(p3d.Box(1.0, 2.0, 3.0)).properties.volume == 48.0


def test_monte_carlo_is_chosen_by_the_library():
    result = p3d.props("sphere:1", method="montecarlo", samples=20_000, seed=1)
    assert result.method == "montecarlo" and result.details == {"samples": 20_000, "seed": 1}
    assert abs(result.properties.volume - 4 / 3 * np.pi) < 5 * result.uncertainty["volume"]


@pytest.mark.parametrize("kwargs, names", [
    (dict(density=1, mass=1), ("mass, density", "exclusive")),
    (dict(samples=10), ("samples, seed, tolerance", "method=montecarlo")),
    (dict(method="magic"), ("method", "unknown method")),
    (dict(method="montecarlo", tessellate=8), ("tessellate", "method=montecarlo")),
])
def test_library_errors_name_parameters_not_flags(kwargs, names):
    with pytest.raises(p3d.UsageError) as info:
        p3d.props(CUBE_V[CUBE_F], **kwargs)
    message = str(info.value)
    assert "--" not in message and all(n in message for n in names)


def test_the_command_line_names_the_flags_for_the_same_errors():
    result = CliRunner().invoke(cli, ["props", "box", "--density", "1", "--mass", "1"])
    assert result.exit_code == 2
    assert result.stderr.startswith("p3d: error: --mass/--density: both given; they are exclusive")
    result = CliRunner().invoke(cli, ["props", "box", "--samples", "10"])
    assert "--samples/--seed/--tolerance: given without --method montecarlo; add --method montecarlo" in result.stderr


def test_bad_things_are_refused_with_a_p3d_error():
    for thing, match in ((object(), "cannot measure"), (np.zeros((4, 3)), r"\(n, 3, 3\)"),
                         ((CUBE_V, CUBE_F + 100), "outside 0..7"), ((CUBE_V, CUBE_F.astype(float)), "integers"),
                         (np.full((2, 3, 3), "x"), r"\(n, 3, 3\) array of numbers")):
        with pytest.raises(p3d.P3DError, match=match):
            p3d.props(thing)


def _all_error_classes():
    found, todo = [], [errors.P3DError]
    while todo:
        cls = todo.pop()
        found.append(cls)
        todo += cls.__subclasses__()
    return found


@pytest.mark.parametrize("cls", _all_error_classes(), ids=lambda c: c.__name__)
def test_every_error_survives_pickle(cls):
    error = cls("part.stl", "something is wrong", "fix it")
    error.extra = 7
    back = pickle.loads(pickle.dumps(error))
    assert type(back) is cls and back.message == error.message == str(back)
    assert (back.where, back.what, back.hint, back.exit_code, back.extra) == (
        "part.stl", "something is wrong", "fix it", cls.exit_code, 7)


def test_import_is_cheap_and_names_load_on_first_use():
    code = ("import sys, p3d_cli as p3d; heavy = [m for m in ('numpy', 'click', 'scipy', 'meshio', 'trimesh') "
            "if m in sys.modules]; print(heavy); p3d.props; print('numpy' in sys.modules, 'click' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split("\n")[:2] == ["[]", "True False"]
    assert set(p3d.__all__) <= set(dir(p3d))
    for name in p3d.__all__:
        assert getattr(p3d, name) is not None
    with pytest.raises(AttributeError):
        p3d.no_such_name  # noqa: B018


def _write_ascii_stl(path, triangles) -> None:
    lines = ["solid box"]
    for t in triangles:
        lines += ["facet normal 0 0 0", "outer loop"] + [f"vertex {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in t]
        lines += ["endloop", "endfacet"]
    path.write_text("\n".join(lines + ["endsolid box", ""]))
