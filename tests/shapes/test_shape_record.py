"""A shape class is the one record of its shape: a class registered with nothing else edited is
parsed from its spec, measured, mirrored as it declares, listed in every message and help that
lists shapes, and public as ``p3d.NAME``. Each check fails if some list elsewhere were still needed."""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
import pytest

import p3d_cli
from p3d_cli import shapes
from p3d_cli.errors import ReadError, SpecError
from p3d_cli.geometry.placement import Mirrored, Placement
from p3d_cli.robots.model import spec
from p3d_cli.shapes import SHAPES, register
from p3d_cli.shapes.box import Box
from p3d_cli.shapes.record import DECLARED

from helpers.real_meshes import REPO


@dataclass(frozen=True)
class Cube(Box):
    """A throwaway shape: the cube of half-edge ``s`` (spec ``cube:S``), declared not mirror
    symmetric so that a mirrored one must be wrapped."""

    name = "cube"
    form = "cube or cube:S (half-edge S)"
    arity = (1,)
    mirror_symmetric = False

    @classmethod
    def from_numbers(cls, text, numbers):
        return cls(numbers[0], numbers[0], numbers[0])

    def numbers(self):
        return (self.sx,)


@pytest.fixture
def cube():
    register(Cube)
    try:
        yield Cube
    finally:
        del SHAPES["cube"]


def test_a_registered_class_is_parsed_from_its_spec(cube):
    assert shapes.parse_shape("cube:2") == Cube(2.0, 2.0, 2.0)
    assert shapes.parse_spec("CUBE") == Cube()
    with pytest.raises(SpecError, match=r"cube takes 1 numbers, got 2 numbers; write cube or cube:S \(half-edge S\); "
                                         r"factors are half-extents"):
        shapes.parse_shape("cube:1,2")
    assert shapes.parse_spec("cube.stl") is None


def test_a_registered_class_is_measured_through_the_public_api(cube):
    assert p3d_cli.props("cube:2").volume == 64.0
    bounds = p3d_cli.bounds("cube:1")
    assert bounds.min.tolist() == [-1.0, -1.0, -1.0] and bounds.max.tolist() == [1.0, 1.0, 1.0]


def test_mirror_symmetry_is_what_the_class_declares(cube, monkeypatch):
    mirror = Placement(scale=np.array([-1.0, 1.0, 1.0]))
    assert isinstance(mirror.shape(Cube()), Mirrored)
    # the classes p3d ships say it of themselves
    assert {name for name, cls in SHAPES.items() if not cls.mirror_symmetric} == {"wedge", "corner", "cube"}
    monkeypatch.setattr(Cube, "mirror_symmetric", True)
    assert mirror.shape(Cube()) == Cube()


def test_every_list_of_shapes_has_a_registered_class(cube):
    assert "cube or cube:S (half-edge S)" in shapes.spec_lines().splitlines()[-1]
    assert shapes.forms()["cube"] == Cube.form
    assert "cube" in shapes.names(polyhedral=True) and "cube" not in shapes.names(polyhedral=False)
    with pytest.raises(SpecError, match=r"shapes are: .*capsule, cube"):
        shapes.parse_shape("cone:1")
    with pytest.raises(ReadError, match=r"shape specs are .*capsule, cube\)"):
        p3d_cli.props(str(REPO / "no-such-file.stl"))


def test_a_registered_class_is_public(cube):
    assert p3d_cli.Cube is Cube
    assert "Cube" in p3d_cli.__all__ and "Cube" in dir(p3d_cli)


def test_an_unregistered_class_is_gone_everywhere():
    assert "cube" not in SHAPES and "Cube" not in p3d_cli.__all__
    with pytest.raises(AttributeError):
        p3d_cli.Cube  # noqa: B018
    assert shapes.parse_spec("cube:1") is None


def test_the_robot_readers_write_a_spec_the_class_reads_back():
    """A reader maps its primitive onto a class; the class, not the reader, says how its spec is
    written (``cylinder:R,R,H``) and at full precision."""
    for shape in (shapes.Cylinder(0.1, 1 / 3), shapes.Sphere(0.25), shapes.Capsule(0.05, 0.2),
                  shapes.Box(0.1, 0.2, 0.3), shapes.Ellipsoid(1, 2, 3), shapes.EllipticCylinder(1, 2, 3),
                  shapes.Wedge(1, 2, 3), shapes.Corner(1, 2, 3)):
        assert shapes.parse_shape(spec(shape)) == shape
    assert spec(shapes.Cylinder(0.1, 1 / 3)) == "cylinder:0.1,0.1,0.3333333333333333"


@pytest.mark.parametrize("attr", DECLARED)
def test_a_class_that_leaves_out_a_declaration_is_refused(attr):
    namespace = {a: getattr(Cube, a) for a in DECLARED if a != attr}
    # A declaration the record's base gives a default (arity, scale_factors) is declared by that.
    bare = type("Bare", (shapes.record.ShapeRecord,), namespace)
    if hasattr(bare, attr):
        assert register(bare) is bare
        del SHAPES[bare.name]
        return
    with pytest.raises(TypeError, match=f"does not declare {attr}"):
        register(bare)
    assert "cube" not in SHAPES


def test_a_taken_name_is_refused():
    clash = type("Clash", (Cube,), {"name": "box"})
    with pytest.raises(TypeError, match="shape name 'box' is taken by Box"):
        register(clash)
    assert SHAPES["box"] is Box


def test_every_shape_has_its_row_in_the_docs():
    """docs/shapes.md's table of specs: a row per class (the docs cannot be built from the
    classes, so they are checked against them)."""
    page = (REPO / "docs" / "shapes.md").read_text()
    rows = set(re.findall(r"^\| `([a-z]+)[:`]", page, re.M))
    assert rows == set(SHAPES)
