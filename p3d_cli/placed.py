"""Placed inputs: a mesh path or a shape spec, scaled, rotated and moved, for props and bounds.

``input_props`` and ``input_bounds`` are the library entries behind ``p3d props`` (with
placement options) and ``p3d bounds``. Both take the text the user gave: a spec
(``p3d_cli.shapes.parse_spec``) or else a mesh path.

Placement order: ``--scale`` first, in the solid's own frame about the origin; then the
rotation about the world origin; then the translation. Mass properties are placed from the
unplaced solid's moments: eq. 9 (``p3d_cli.moments.scale_moments``) for the scale,
``C' = R C Rᵀ`` for the rotation (so ``I' = R I Rᵀ``), and the centre moved by the translation.
"""

from __future__ import annotations

import dataclasses
import os
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from p3d_cli.bounds import BoundsResult, check_scale, placed_shape, triangles_bounds
from p3d_cli.errors import InputError, SpecError, UsageError
from p3d_cli.massprops import mass_properties
from p3d_cli.mesh.integrals import triangle_moments
from p3d_cli.moments import rotate_moments, scale_moments, translate_moments
from p3d_cli.results import Bounds, MeshFacts, Moments, PropsResult
from p3d_cli.props import exact_uncertainty
from p3d_cli.shapes import FORMS, SHAPES, looks_like_spec, parse_spec


@dataclass(frozen=True)
class Placement:
    """Scale, then rotation about the origin, then translation.

    Attributes
    ----------
    scale : (3,) float64 or None
        Positive diagonal scale factors.
    rotation : (3, 3) float64 or None
        A proper rotation matrix (``p3d_cli.rotation``).
    translation : (3,) float64 or None
    """

    scale: np.ndarray | None = None
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.scale is not None:
            object.__setattr__(self, "scale", check_scale(self.scale))
        if self.rotation is not None:
            object.__setattr__(self, "rotation", np.asarray(self.rotation, dtype=np.float64).reshape(3, 3))
        if self.translation is not None:
            object.__setattr__(self, "translation", np.asarray(self.translation, dtype=np.float64).reshape(3))

    def describe(self) -> dict:
        """The placement for the record: only the parts that were given."""
        parts = {"scale": self.scale, "rotation": self.rotation, "translation": self.translation}
        return {name: value for name, value in parts.items() if value is not None}

    @property
    def is_identity(self) -> bool:
        return self.scale is None and self.rotation is None and self.translation is None

    def moments(self, moments: Moments) -> Moments:
        """The placed solid's moments (eq. 9, then ``R C Rᵀ``, then the centre moved)."""
        return place_moments(moments, self.scale, self.rotation, self.translation)

    def shape_bounds(self, shape) -> Bounds:
        """Exact bounds of the placed shape (closed forms or vertex projection)."""
        return placed_shape(shape, self.scale).bounds(self.rotation, self.translation)

    def triangles_bounds(self, blocks) -> Bounds:
        """Exact bounds of the placed triangles (vertex projection)."""
        return triangles_bounds(blocks, self.scale, self.rotation, self.translation)


def place_moments(moments: Moments, scale=None, rotation=None, translation=None) -> Moments:
    """Moments after a diagonal scale, a rotation about the origin and a translation.

    Parameters
    ----------
    moments : Moments
    scale : (3,) array_like, optional
        Eq. 9: exact for any diagonal scale (FACTS.md).
    rotation : (3, 3) array_like, optional
    translation : (3,) array_like, optional
    """
    if scale is not None:
        moments = scale_moments(moments, check_scale(scale))
    if rotation is not None:
        moments = rotate_moments(moments, rotation)
    if translation is not None:
        moments = translate_moments(moments, translation)
    return moments


def placed_mass_properties(moments: Moments, placement: Placement | None = None, *,
                           density: float | None = None, mass: float | None = None, about=None):
    """``massprops.mass_properties`` of the placed solid (I' = R I Rᵀ about the moved centre)."""
    placed = moments if placement is None else placement.moments(moments)
    return mass_properties(placed, density=density, mass=mass, about=about)


def resolve_spec(source: str):
    """The shape ``source`` names, or None for a path.

    Raises
    ------
    SpecError
        A malformed spec, or ``word:numbers`` text naming neither a shape nor an existing file.
    """
    shape = parse_spec(source)
    if shape is None and looks_like_spec(source) and ":" in source and not os.path.exists(source):
        name = source.split(":", 1)[0]
        raise SpecError(source, f"no shape named {name!r} and no such file",
                        "shapes are: " + ", ".join(SHAPES) + "; write ./" + source + " for a file")
    return shape


def spec_warnings(source: str) -> list[str]:
    """A file named like a spec is shadowed by the spec; say so and how to reach it."""
    if os.path.exists(source):
        return [f"{source!r} is read as a shape spec, not as the file of that name; "
                f"write ./{source} for the file"]
    return []


def shape_triangles(shape, tessellate: int) -> np.ndarray:
    """The polyhedron standing in for ``shape``: its own faces, or ``tessellate`` segments."""
    if shape.polyhedral:
        return shape.triangles()
    return shape.tessellate(tessellate)


def watch_bounds(mesh, placement: Placement):
    """``mesh`` with its blocks also projected as they stream past, and a getter for the bounds.

    One pass serves both the integrals and the placed bounds, so standard input (which reads
    once) and large files are not read twice.
    """
    seen: list[Bounds] = []
    if mesh.tetrahedra is not None:
        return mesh, lambda: placement.triangles_bounds(np.asarray(mesh.tetrahedra))

    def blocks() -> Iterator[np.ndarray]:
        seen.clear()
        for block in mesh.read_blocks():
            if len(block):
                seen.append(placement.triangles_bounds(block))
            yield block

    def bounds() -> Bounds | None:
        if not seen:
            return None
        return Bounds(np.min([b.min for b in seen], axis=0), np.max([b.max for b in seen], axis=0))

    return dataclasses.replace(mesh, read_blocks=blocks), bounds


def shape_props(shape, source: str, placement: Placement | None = None, *, tessellate: int | None = None,
                density: float | None = None, mass: float | None = None, about=None) -> PropsResult:
    """Mass properties of a shape: exact closed forms, or its tessellated stand-in.

    Parameters
    ----------
    shape : Shape
    source : str
        The spec as the user wrote it (for the output).
    placement : Placement, optional
    tessellate : int, optional
        Replace a round shape by an inscribed polyhedron of this many segments (a polyhedral
        shape is replaced by its own faces, which changes nothing).
    """
    placement = placement or Placement()
    warnings = spec_warnings(source)
    if tessellate is not None:
        triangles = shape_triangles(shape, tessellate)
        unplaced = triangle_moments(triangles)
        moments = placement.moments(unplaced)
        props = mass_properties(moments, density=density, mass=mass, about=about)
        facts = MeshFacts(source, "tessellated", len(triangles), True,
                          placement.triangles_bounds(triangles))
        return PropsResult(facts, props, "exact", tuple(warnings), exact_uncertainty(moments, props))
    moments = placement.moments(shape.moments())
    props = mass_properties(moments, density=density, mass=mass, about=about)
    facts = MeshFacts(source, "primitive", 0, None, placement.shape_bounds(shape))
    return PropsResult(facts, props, "exact", tuple(warnings), None)


def input_props(source: str, placement: Placement | None = None, *, tessellate: int | None = None,
                fmt: str | None = None, density: float | None = None, mass: float | None = None,
                about=None, stdin=None) -> PropsResult:
    """Mass properties of a spec or a mesh file, placed.

    Raises
    ------
    SpecError, UsageError, InputError
    """
    placement = placement or Placement()
    shape = resolve_spec(source)
    details = {} if placement.is_identity else {"placement": placement.describe()}
    if shape is not None:
        if tessellate is not None:
            details["tessellate"] = tessellate
        result = shape_props(shape, source, placement, tessellate=tessellate, density=density,
                             mass=mass, about=about)
        return dataclasses.replace(result, details={**result.details, **details})
    _refuse_tessellate(source, tessellate)
    from p3d_cli.props import mesh_props

    result = mesh_props(source, fmt=fmt, density=density, mass=mass, about=about, stdin=stdin,
                        placement=None if placement.is_identity else placement)
    return dataclasses.replace(result, details={**result.details, **details})


def input_bounds(source: str, placement: Placement | None = None, *, tessellate: int | None = None,
                 fmt: str | None = None, stdin=None) -> BoundsResult:
    """Exact axis-aligned bounds of a spec or a mesh file, placed.

    Raises
    ------
    SpecError, UsageError, InputError
    """
    placement = placement or Placement()
    shape = resolve_spec(source)
    if shape is not None:
        warnings = tuple(spec_warnings(source))
        if tessellate is not None:
            triangles = shape_triangles(shape, tessellate)
            return BoundsResult(source, "tessellated", "vertices", placement.triangles_bounds(triangles),
                                len(triangles), warnings)
        method = "vertices" if shape.polyhedral else "closed form"
        return BoundsResult(source, "primitive", method, placement.shape_bounds(shape), 0, warnings)
    _refuse_tessellate(source, tessellate)
    from p3d_cli.io import load_mesh

    mesh = load_mesh(source, fmt, stdin=stdin)
    where = "<stdin>" if source == "-" else source
    if mesh.tetrahedra is not None:
        blocks = (np.asarray(mesh.tetrahedra),)
    else:
        blocks = _finite_blocks(mesh.read_blocks(), where)
    try:
        bounds = placement.triangles_bounds(blocks)
    except ValueError:
        raise InputError(where, "the mesh has no faces", "export it again with its faces") from None
    return BoundsResult(source, mesh.format, "vertices", bounds, mesh.face_count, tuple(mesh.warnings))


def _finite_blocks(blocks, where: str) -> Iterator[np.ndarray]:
    """The blocks, refusing the first NaN or infinite coordinate (with its face index)."""
    seen = 0
    for block in blocks:
        finite = np.isfinite(block).reshape(len(block), -1).all(axis=1)
        if not finite.all():
            bad = int(np.flatnonzero(~finite)[0])
            raise InputError(where, f"face {seen + bad} has a NaN or infinite coordinate",
                             "repair or re-export the mesh")
        seen += len(block)
        yield block


def _refuse_tessellate(source: str, tessellate) -> None:
    if tessellate is not None:
        round_names = ", ".join(n for n, c in SHAPES.items() if not c.polyhedral)
        raise UsageError("--tessellate", f"{source} is a mesh, already polyhedral",
                         f"--tessellate applies to shape specs ({round_names})")


__all__ = ["Placement", "place_moments", "placed_mass_properties", "input_props", "input_bounds",
           "shape_props", "resolve_spec", "FORMS"]
