"""parse_spec: what is a spec, what is a path, and the refusals (naming the rule)."""

import pytest

from p3d_cli.errors import SpecError
from p3d_cli.shapes import (SHAPES, Box, Corner, Cylinder, Ellipsoid, EllipticCylinder, Sphere,
                            Wedge, parse_spec)


@pytest.mark.parametrize("text, shape", [
    ("box", Box()),
    ("box:1,2,3", Box(1.0, 2.0, 3.0)),
    ("BOX:1, 2, 3", Box(1.0, 2.0, 3.0)),
    ("wedge:1e-3,2,3", Wedge(1e-3, 2.0, 3.0)),
    ("corner", Corner()),
    ("cylinder:2,2,5", Cylinder(2.0, 5.0)),
    ("cylinder", Cylinder()),
    ("sphere", Sphere()),
    ("sphere:0.5", Sphere(0.5)),
    ("sphere:2,2,2", Sphere(2.0)),
    ("ellipsoid:1,2,3", Ellipsoid(1.0, 2.0, 3.0)),
    ("ecylinder:1,2,3", EllipticCylinder(1.0, 2.0, 3.0)),
])
def test_specs(text, shape):
    assert parse_spec(text) == shape


@pytest.mark.parametrize("text", ["./box", "box.stl", "dir/box:1,2,3", "part", "C:\\box", "",
                                  "cube:1,2,3", "box 1"])
def test_not_specs(text):
    assert parse_spec(text) is None


@pytest.mark.parametrize("text, words", [
    ("box:1,2", ["takes 3 numbers", "box:SX,SY,SZ"]),
    ("sphere:1,2", ["takes 1 or 3 numbers"]),
    ("box:-1,1,1", ["not positive"]),
    ("box:0,1,1", ["not positive"]),
    ("box:a,1,1", ["not a number"]),
    ("box:", ["not a number"]),
    ("box:nan,1,1", ["not finite"]),
    ("box:inf,1,1", ["not finite"]),
    ("sphere:1,2,3", ["sx = sy = sz", "ellipsoid:1,2,3"]),
    ("cylinder:1,2,3", ["sx = sy", "ecylinder:1,2,3"]),
])
def test_refusals_say_what_and_how(text, words):
    with pytest.raises(SpecError) as info:
        parse_spec(text)
    assert info.value.where == text
    for w in words:
        assert w in info.value.message


def test_every_registered_class_has_its_name():
    for name, cls in SHAPES.items():
        assert cls.name == name
        shape = cls()
        assert parse_spec(shape.spec()) == shape
        assert hash(shape) == hash(cls())          # frozen values
