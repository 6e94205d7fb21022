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

from p3d_cli.errors import SpecError
from p3d_cli.shapes import classes
from p3d_cli.shapes.classes import *  # noqa: F403 - the classes, by their own names (p3d_cli.shapes.Box)
from p3d_cli.shapes.record import ShapeRecord, check_declared

#: Any shape (the classes of ``shapes.classes`` all subclass it).
Shape = ShapeRecord

#: Spec name -> shape class, built from ``shapes.classes`` (``register`` adds one).
SHAPES: dict[str, type[Shape]] = {}


def register(cls: type[Shape]) -> type[Shape]:
    """Add the shape class ``cls`` under its spec name (``cls.name``): every list of shapes p3d
    gives (spec parsing, messages, help, the public ``p3d.NAME``) then has it.

    Raises
    ------
    TypeError
        ``cls`` leaves out a declaration (``p3d_cli.shapes.record``), or its name is taken.
    """
    check_declared(cls)
    if SHAPES.get(cls.name, cls) is not cls:
        raise TypeError(f"shape name {cls.name!r} is taken by {SHAPES[cls.name].__name__}")
    SHAPES[cls.name] = cls
    return cls


for _cls in vars(classes).values():
    if isinstance(_cls, type) and issubclass(_cls, ShapeRecord):
        register(_cls)
del _cls


def forms() -> dict[str, str]:
    """Spec name -> the written form of its spec, for messages and help."""
    return {name: cls.form for name, cls in SHAPES.items()}


def spec_lines(indent: str = "  ") -> str:
    """The shapes' spec forms, one a line, for a command's help."""
    return "\n".join(indent + cls.form for cls in SHAPES.values())


def names(polyhedral: bool | None = None) -> list[str]:
    """The spec names, or those of the polyhedral (True) or the round (False) shapes only."""
    return [name for name, cls in SHAPES.items() if polyhedral is None or cls.polyhedral == polyhedral]


def public_classes() -> dict[str, type[Shape]]:
    """Class name -> class: the names ``p3d_cli`` gives the shapes (``p3d.Box``)."""
    return {cls.__name__: cls for cls in SHAPES.values()}


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
    cls = SHAPES[name]
    hint = f"write {cls.form}" + ("; factors are half-extents of the canonical [-1, 1]³ shape"
                                  if cls.scale_factors else "")
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
    counts = cls.arity
    if len(values) not in counts:
        got = f"{len(values)} number{'s' if len(values) != 1 else ''}"
        raise SpecError(text, f"{name} takes {' or '.join(map(str, counts))} numbers, got {got}", hint)
    return values


def _build(text: str, name: str, f: list[float]) -> Shape:
    return SHAPES[name].from_numbers(text, f)


__all__ = ["SHAPES", "Shape", "register", "forms", "spec_lines", "names", "public_classes", "parse_shape",
           "parse_spec", "looks_like_spec", *public_classes()]
