"""Shape classes: one module per class, and the one registry naming them (``SHAPES``).

A spec names a shape where a mesh path would go: ``NAME`` (unit scale) or
``NAME:SX,SY,SZ`` with the Physics3D note's scale factors, the half-extents of the canonical
solid in [-1, 1]³ (docs/method.md, "Scale factors"): ``box:1,2,3`` measures 2 × 4 × 6. ``sphere:R`` gives a radius.
``capsule:R,H`` is the exception: a radius and the half-length of its cylindrical part.

The note's scale rules keep circles circular: a sphere needs sx = sy = sz and a cylinder
(axis z) sx = sy. Breaking them is refused, naming the rule and the exact generalisation p3d
offers under its own name: ``ellipsoid:A,B,C`` and ``ecylinder:A,B,H`` (semi-axes A, B, C or
half-height H). Eq. 9 is exact for any diagonal scale, and both have closed-form bounds.

Every class is a frozen dataclass with ``moments()``, ``bounds(rotation, translation)``,
``inside(points)``, ``scaled(scale)`` and ``spec()``; polyhedral ones (``polyhedral = True``)
add ``vertices()`` and ``triangles()``, round ones ``tessellate(n)``.
"""

from __future__ import annotations

import math
import re
from typing import Union

from p3d_cli.errors import SpecError
from p3d_cli.shapes.box import Box
from p3d_cli.shapes.capsule import Capsule
from p3d_cli.shapes.corner import Corner
from p3d_cli.shapes.cylinder import Cylinder
from p3d_cli.shapes.ellipsoid import Ellipsoid
from p3d_cli.shapes.elliptic_cylinder import EllipticCylinder
from p3d_cli.shapes.sphere import Sphere
from p3d_cli.shapes.wedge import Wedge

Shape = Union[Box, Wedge, Corner, Cylinder, Sphere, Ellipsoid, EllipticCylinder, Capsule]

#: Spec name -> shape class.
SHAPES: dict[str, type[Shape]] = {
    "box": Box,
    "wedge": Wedge,
    "corner": Corner,
    "cylinder": Cylinder,
    "sphere": Sphere,
    "ellipsoid": Ellipsoid,
    "ecylinder": EllipticCylinder,
    "capsule": Capsule,
}

#: The written form of each spec, for messages and help.
FORMS = {
    "box": "box or box:SX,SY,SZ",
    "wedge": "wedge or wedge:SX,SY,SZ",
    "corner": "corner or corner:SX,SY,SZ",
    "cylinder": "cylinder or cylinder:R,R,H (radius R about z, half-height H)",
    "sphere": "sphere, sphere:R or sphere:R,R,R",
    "ellipsoid": "ellipsoid or ellipsoid:A,B,C (semi-axes)",
    "ecylinder": "ecylinder or ecylinder:A,B,H (semi-axes A, B about z, half-height H)",
    "capsule": "capsule or capsule:R,H (radius R about z, H the half-length of the cylindrical part)",
}

_SPEC = re.compile(r"^([A-Za-z]+)(?::(.*))?$")


def looks_like_spec(text: str) -> bool:
    """True when ``text`` has a spec's form (``word`` or ``word:...``) and no path separator.

    Such text that is not a registered name is still a file name to try; this only tells
    the caller whether an unknown ``cube:1,2,3`` deserves a message about shapes.
    """
    return "/" not in text and "\\" not in text and _SPEC.match(text) is not None


def parse_spec(text: str) -> Shape | None:
    """The shape a spec names, or None when ``text`` is not a spec (so is a path).

    Not a spec: text with a path separator (``./box`` reaches a file named ``box``), or whose
    part before any ``:`` is not a registered name (``part.stl``, ``C:\\part.stl``).

    Parameters
    ----------
    text : str

    Returns
    -------
    Shape or None

    Raises
    ------
    SpecError
        A registered name with malformed numbers, a wrong count, a non-positive or non-finite
        factor, or factors that break the sphere's or the cylinder's scale rule.
    """
    if "/" in text or "\\" in text:
        return None
    match = _SPEC.match(text)
    if match is None or match.group(1).lower() not in SHAPES:
        return None
    name = match.group(1).lower()
    if match.group(2) is None:
        return SHAPES[name]()
    factors = _numbers(text, name, match.group(2))
    return _build(text, name, factors)


def parse_shape(text: str) -> Shape:
    """The shape a spec names (``"box:1,2,3"``, ``"sphere:0.5"``).

    Raises
    ------
    SpecError
        ``text`` is not a spec (names no shape), or is a malformed one.
    """
    shape = parse_spec(text)
    if shape is None:
        name = text.split(":", 1)[0]
        raise SpecError(text, f"no shape named {name!r}", "shapes are: " + ", ".join(SHAPES))
    return shape


def _numbers(text: str, name: str, body: str) -> list[float]:
    hint = f"write {FORMS[name]}" + ("" if name == "capsule" else
                                      "; factors are half-extents of the canonical [-1, 1]³ shape")
    values = []
    for part in body.split(","):
        try:
            value = float(part.strip())
        except ValueError:
            raise SpecError(text, f"{part.strip()!r} is not a number", hint) from None
        if not math.isfinite(value):
            raise SpecError(text, f"scale factor {part.strip()!r} is not finite", hint)
        if value == 0 and any(c in "123456789" for c in part.split("e")[0].split("E")[0]):
            raise SpecError(text, f"scale factor {part.strip()} underflows to 0 in float64",
                            "give the size in a smaller unit, above 1e-300")
        if value <= 0:
            raise SpecError(text, f"scale factor {part.strip()} is not positive",
                            "scale factors are half-extents and must be > 0 "
                            "(to mirror, place the shape with a negative scale)")
        values.append(value)
    counts = {"sphere": (1, 3), "capsule": (2,)}.get(name, (3,))
    if len(values) not in counts:
        got = f"{len(values)} number{'s' if len(values) != 1 else ''}"
        raise SpecError(text, f"{name} takes {' or '.join(map(str, counts))} numbers, got {got}", hint)
    return values


def _build(text: str, name: str, f: list[float]) -> Shape:
    if name == "sphere":
        if len(f) == 1:
            return Sphere(f[0])
        if not f[0] == f[1] == f[2]:
            raise SpecError(text, "a sphere keeps sx = sy = sz (circles stay circles)",
                            f"write sphere:R, or ellipsoid:{_join(f)} for the ellipsoid")
        return Sphere(f[0])
    if name == "cylinder":
        if f[0] != f[1]:
            raise SpecError(text, "a cylinder (axis z) keeps sx = sy (circles stay circles)",
                            f"write cylinder:R,R,H, or ecylinder:{_join(f)} for the elliptic cylinder")
        return Cylinder(f[0], f[2])
    if name == "capsule":
        return Capsule(f[0], f[1])
    return SHAPES[name](*f)  # type: ignore[arg-type]  # the three-factor classes


def _join(values) -> str:
    return ",".join(f"{v:g}" for v in values)


__all__ = ["SHAPES", "FORMS", "Shape", "parse_shape", "parse_spec", "looks_like_spec", "Box", "Wedge", "Corner",
           "Cylinder", "Sphere", "Ellipsoid", "EllipticCylinder", "Capsule"]
