"""Mass properties of scene bodies, computed only when a solve needs them.

A body that gives ``mass``, ``inertia`` and ``center_of_mass`` is never integrated. A shape is
integrated at most once per distinct primitive spec or mesh file in one resolve, and only for
the bodies asked for (fixed bodies need nothing; resting unconstrained bodies need nothing).
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from p3d_cli.errors import P3DError, RangeError, SceneError
from p3d_cli.geometry.inertia import mass_properties
from p3d_cli.results import Moments


@dataclass(frozen=True)
class Inertial:
    """Resolved mass properties of a free body.

    Attributes
    ----------
    mass : float
    inertia : (3, 3) float64
        About the centre of mass, body axes (positive tensor).
    center_of_mass : (3,) float64
        Body frame.
    """

    mass: float
    inertia: np.ndarray
    center_of_mass: np.ndarray


def parse_shape_spec(text: str, where: str):
    """The primitive shape ``text`` names, or None when it is a mesh path.

    Raises
    ------
    SceneError
        ``text`` names a primitive but its numbers are malformed.
    """
    from p3d_cli.shapes import parse_spec

    try:
        return parse_spec(text)
    except P3DError as exc:
        raise SceneError(where, f"{text!r}: {exc.what}", exc.hint) from None


def shape_moments(spec_or_path: str, where: str) -> Moments:
    """Volume moments of a primitive spec, or of a mesh file.

    Parameters
    ----------
    spec_or_path : str
        A primitive spec, or a mesh path as the scene resolved it (``BodySpec.shape_path``).
    where : str
        The place in the scene, for messages.

    Raises
    ------
    SceneError
        Unreadable or corrupt mesh, or a solid with no positive volume.
    """
    from p3d_cli.geometry.moments import shape_moments as closed_form

    shape = parse_shape_spec(spec_or_path, where)
    # Out-of-range moments end in one RangeError (checked where they are made), as for p3d props:
    # numpy's overflow warnings on the way would only repeat it.
    with np.errstate(all="ignore"):
        if shape is not None:
            try:   # closed forms: p3d_cli.measure.exact (and the mesh readers it imports) is not needed
                moments = closed_form(shape, spec_or_path)
            except RangeError as exc:      # named by the body that gives the shape
                raise RangeError(where, f"{spec_or_path!r}: {exc.what}", exc.hint) from None
        else:
            from p3d_cli.measure import as_solid, solid_moments

            try:
                moments = solid_moments(as_solid(spec_or_path))
            except P3DError as exc:
                raise SceneError(where, f"cannot use mesh {spec_or_path!r}: {exc.message}",
                                 "fix or re-export the mesh") from None
    if moments.is_empty or moments.volume <= 0:
        what = ("encloses no volume" if moments.is_empty else
                "has negative signed volume (faces wound inward)")
        raise SceneError(where, f"{spec_or_path!r} {what}, so it has no mass",
                         "use a closed, outward-wound mesh, or give mass:, inertia: and center_of_mass:")
    return moments


def shape_key(body) -> str:
    """What identifies a body's shape for the once-per-file cache."""
    return os.path.realpath(body.shape_path) if body.shape_path else body.shape


def resolve_inertials(bodies) -> dict:
    """``Inertial`` of each body given, integrating each distinct shape once.

    Parameters
    ----------
    bodies : iterable of BodySpec
        Free bodies whose mass properties are needed, or fixed ones whose centre is needed
        (a fixed body gets an ``Inertial`` with mass ``inf``).

    Returns
    -------
    dict
        Body name -> Inertial.
    """
    cache: dict[str, Moments] = {}
    out = {}
    for body in bodies:
        out[body.name] = _inertial(body, cache)
    return out


def _inertial(body, cache) -> Inertial:
    if body.parts is not None:
        return _parts_inertial(body)
    need_shape = body.shape is not None and (
        body.center_of_mass is None or (not body.fixed and (body.inertia is None or body.mass is None)))
    moments = None
    if need_shape:
        key = shape_key(body)
        if key not in cache:
            cache[key] = shape_moments(body.shape_path or body.shape, f"{body.where}.shape")
        moments = cache[key]
    com = body.center_of_mass
    if com is None:
        com = moments.center.copy() if moments is not None else np.zeros(3)
    if body.fixed:
        return Inertial(float("inf"), np.full((3, 3), np.inf), com)
    mass = body.mass
    inertia = body.inertia
    if moments is not None and (mass is None or inertia is None):
        with np.errstate(all="ignore"):     # an overflow is one RangeError from mass_properties
            props = mass_properties(moments, density=None if mass is not None else body.density, mass=mass,
                                    where=body.where)
        mass = props.mass if mass is None else mass
        inertia = props.inertia if inertia is None else inertia
    return Inertial(float(mass), np.asarray(inertia, dtype=np.float64), np.asarray(com, dtype=np.float64))


#: Warning codes of a part that make it no solid for a body.
NOT_A_SOLID = frozenset({"open", "inward", "flat", "self-intersecting", "implausible", "inverted-tetrahedra"})


def _parts_inertial(body) -> Inertial:
    """A body made of parts, measured as an assembly in the body's frame (``p3d_cli.measure.props``).

    The body's ``density`` is the default of the parts that give none, its ``mass`` the
    whole's; ``inertia`` and ``center_of_mass``, when given, override what the parts give.
    """
    from p3d_cli.measure import props

    where = f"{body.where}.parts"
    try:
        with np.errstate(all="ignore"):     # an overflow is one RangeError, as for a shape
            result = props(body.parts, density=body.density, mass=body.mass)
    except SceneError:
        raise
    except P3DError as exc:
        raise SceneError(exc.where if exc.where.startswith(body.where) else where, exc.what, exc.hint) from None
    # A scene has nowhere to show a warning, and a body needs a solid: a part that is not one
    # (open, wound inward, flat, self-intersecting) is refused, as a body's shape: is.
    for index, part in enumerate(result.parts):
        bad = [w for w in part.warnings if w.code in NOT_A_SOLID]
        if bad:
            raise SceneError(f"{where}[{index}]" if len(body.parts.parts) == len(result.parts) else where,
                             f"{part.details.get('name', part.facts.source)}: {bad[0]}",
                             "use closed, outward-wound meshes, or give mass:, inertia: and center_of_mass:")
    whole = result.properties
    if not whole.mass > 0 or whole.center_of_mass is None or whole.inertia is None:
        raise SceneError(where, "the parts have no positive mass together",
                         "use closed, outward-wound meshes, or give mass:, inertia: and center_of_mass:")
    com = body.center_of_mass if body.center_of_mass is not None else whole.center_of_mass
    if body.fixed:
        return Inertial(float("inf"), np.full((3, 3), np.inf), np.asarray(com, dtype=np.float64))
    inertia = body.inertia if body.inertia is not None else whole.inertia
    return Inertial(float(whole.mass), np.asarray(inertia, dtype=np.float64), np.asarray(com, dtype=np.float64))
