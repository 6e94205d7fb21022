"""Placements from what users write: the command line's options and an assembly's or scene's
mapping (``translate``, ``rotate``, ``quat``, ``rpy``, ``scale``), one parser for both, into
``p3d_cli.geometry.placement.Placement``.
"""

from __future__ import annotations

import numpy as np

from p3d_cli.errors import UsageError
from p3d_cli.geometry.placement import IDENTITY, Placement, check_scale


def make_placement(*, scale=None, turns=None, quat=None, rpy=None, translate=None,
                   names: tuple[str, str, str] = ("rotate", "quat", "rpy")) -> Placement | None:
    """The one parser of placement text: the ``Placement`` of these values, or None for none.

    Parameters
    ----------
    scale : float or (3,) array_like, optional
        One factor (uniform) or three; negative factors mirror.
    turns : iterable of str, optional
        ``AXIS:DEGREES`` turns, each after the previous about the world axes.
    quat : str, optional
        ``W,X,Y,Z``.
    rpy : str, optional
        ``R,P,Y`` radians (URDF: fixed axes x, then y, then z).
    translate : (3,) array_like, optional
    names : three str
        How the caller names ``turns``, ``quat`` and ``rpy`` in the error when several are given.

    Raises
    ------
    UsageError
        A malformed turn, quaternion or rpy, a zero scale, or the rotation given two ways.
    """
    from p3d_cli.geometry.rotation import compose_rotations, parse_quaternion, parse_rpy, parse_turn

    given = [n for n, v in zip(names, (turns, quat, rpy)) if v]
    if len(given) > 1:
        raise UsageError("/".join(given), "both given" if len(given) == 2 else "all given",
                         f"give the rotation one way: {' or '.join(given)}")
    rotation = None
    if turns:
        rotation = compose_rotations(parse_turn(t) for t in turns)
    elif quat:
        rotation = parse_quaternion(quat)
    elif rpy:
        rotation = parse_rpy(rpy)
    if scale is None and rotation is None and translate is None:
        return None
    return Placement(None if scale is None else check_scale(scale), rotation, translate)


#: The placement keys of a part or a body in a YAML file.
PLACEMENT_KEYS = ("translate", "rotate", "quat", "rpy", "scale")


def placement_from_mapping(entry: dict, where: str) -> Placement:
    """The placement of a YAML mapping's ``translate``, ``rotate``, ``quat``, ``rpy``, ``scale``.

    ``rotate`` is ``{axis: z, degrees: 30}`` (axis a name or ``[x, y, z]``), the text ``z:30``,
    or a list of those turns (each after the previous, about the world axes); ``quat`` is
    ``[w, x, y, z]``; ``rpy`` is ``[roll, pitch, yaw]`` in radians (URDF); ``scale`` one number
    or three (negative mirrors); ``translate`` three numbers. The values become the text the
    command line takes and go through ``make_placement``: one parser for every road.

    Raises
    ------
    InputError
        A bad value, named ``where.key``.
    """
    from p3d_cli.errors import InputError, P3DError

    def numbers(key: str, counts: tuple[int, ...]) -> list[float] | None:
        value = entry.get(key)
        if value is None:
            return None
        items = value if isinstance(value, list) else [value]
        if len(items) not in counts or not all(_is_number(v) and np.isfinite(v) for v in items):
            raise InputError(f"{where}.{key}", f"expected {' or '.join(map(str, counts))} finite numbers, "
                             f"got {value!r}", "write a list of numbers, e.g. [0, 0, 1]")
        return [float(v) for v in items]

    def text(values: list[float] | None) -> str | None:
        return None if values is None else ",".join(repr(v) for v in values)

    key = "rotate"
    try:
        turns = _turns(entry.get("rotate"))
        translate, scale = numbers("translate", (3,)), numbers("scale", (1, 3))
        quat, rpy = text(numbers("quat", (4,))), text(numbers("rpy", (3,)))
        key = "placement"
        placement = make_placement(scale=scale, turns=turns, quat=quat, rpy=rpy, translate=translate)
    except InputError:
        raise
    except P3DError as exc:
        named = exc.where if all(n in PLACEMENT_KEYS for n in exc.where.split("/")) else key
        raise InputError(f"{where}.{named}", exc.what, exc.hint) from None
    return IDENTITY if placement is None else placement


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _turns(value) -> list[str] | None:
    """``rotate:`` values as ``AXIS:DEGREES`` text."""
    if value is None:
        return None
    items = value if isinstance(value, list) and not all(_is_number(v) for v in value) else [value]
    out = []
    for item in items:
        if isinstance(item, str):
            out.append(item)
        elif isinstance(item, dict) and set(item) == {"axis", "degrees"} and _is_number(item["degrees"]):
            axis = item["axis"]
            if isinstance(axis, list) and len(axis) == 3 and all(_is_number(a) for a in axis):
                axis = ",".join(repr(float(a)) for a in axis)
            if not isinstance(axis, str):
                raise UsageError("rotate", f"axis {axis!r} is neither x, y, z nor three numbers",
                                 "write {axis: z, degrees: 30}")
            out.append(f"{axis}:{float(item['degrees'])!r}")
        else:
            raise UsageError("rotate", f"{item!r} is not a turn", "write {axis: z, degrees: 30} or z:30")
    return out
