"""What every shape class declares: the one record of a shape.

A shape class states, beside its maths (``moments``, ``bounds``, ``inside``, ``scaled``,
``spec``), every fact the rest of p3d needs about it, as class attributes:

- ``name``: its spec name (``box``), the key of ``SHAPES``;
- ``form``: its spec's written form, for help and messages (``box or box:SX,SY,SZ``);
- ``arity``: how many numbers a spec may give (``(3,)``; the sphere's ``(1, 3)``);
- ``scale_factors``: whether those numbers are the Physics3D note's scale factors, the
  half-extents of the canonical solid in [-1, 1]³ (messages then say so; a capsule's are not);
- ``mirror_symmetric``: whether each coordinate-plane reflection leaves it unchanged, so that a
  negative scale factor needs no ``Mirrored`` stand-in (``p3d_cli.geometry.placement``);
- ``polyhedral``: whether it is a polyhedron (``vertices``, ``triangles``) or round
  (``tessellate``);

and ``from_numbers(text, numbers)``, which builds it from a spec's numbers (refusing those that
break its own rules), and ``numbers()``, the numbers of its spec. ``check_declared`` refuses a
class that leaves one out, so a shape is never half registered.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

if TYPE_CHECKING:
    from p3d_cli.results import Bounds, Moments

#: The class attributes a shape class must declare.
DECLARED = ("name", "form", "arity", "scale_factors", "mirror_symmetric", "polyhedral")


class ShapeRecord:
    """The declarations and the protocol every shape class has (subclassed by each).

    The defaults: a spec of three scale factors, read into the constructor in order, given back
    as the ``scale`` (half-extents of the bounding box).
    """

    name: ClassVar[str]
    form: ClassVar[str]
    arity: ClassVar[tuple[int, ...]] = (3,)
    scale_factors: ClassVar[bool] = True
    mirror_symmetric: ClassVar[bool]
    polyhedral: ClassVar[bool]

    @classmethod
    def from_numbers(cls, text: str, numbers: list[float]) -> ShapeRecord:
        """The shape a spec's numbers give (already checked finite, positive, ``arity`` many).

        Raises
        ------
        SpecError
            The numbers break the class's own rule (a sphere's sx = sy = sz).
        """
        return cls(*numbers)

    def numbers(self) -> tuple[float, ...]:
        """The numbers of this shape's spec (``parse_spec`` of them gives the shape back)."""
        return tuple(float(v) for v in self.scale)

    @property
    def scale(self) -> np.ndarray:
        """Half-extents of the bounding box, ``(3,) float64``."""
        raise NotImplementedError

    def spec(self) -> str:
        raise NotImplementedError

    def scaled(self, scale) -> ShapeRecord:
        raise NotImplementedError

    def moments(self) -> Moments:
        raise NotImplementedError

    def bounds(self, rotation=None, translation=None) -> Bounds:
        raise NotImplementedError

    def inside(self, points) -> np.ndarray:
        raise NotImplementedError


def check_declared(cls: Any) -> Any:
    """``cls``, or ``TypeError`` naming what it does not declare."""
    missing = [attr for attr in DECLARED if not hasattr(cls, attr)]
    if missing:
        raise TypeError(f"shape class {cls.__name__} does not declare {', '.join(missing)} "
                        "(p3d_cli.shapes.record)")
    name = cls.name
    if not (isinstance(name, str) and name.isalpha() and name == name.lower()):
        raise TypeError(f"shape class {cls.__name__}: name {name!r} is not a lower-case word")
    return cls


def written(values) -> str:
    """Numbers as a spec writes them in a message: ``1,2,3``."""
    return ",".join(f"{v:g}" for v in values)
