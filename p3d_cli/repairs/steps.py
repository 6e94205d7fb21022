"""The steps of ``p3d repair``, in the one order they run, and the ``steps=`` grammar.

The order is fixed because each step needs the one before: welding can make faces
degenerate or duplicate; degenerate and duplicate faces make edges look non-manifold or
boundary; orientation needs every edge between two faces; a hole is filled against the
orientation of the faces around it; and "outward" needs closed shells to tell inside from
outside.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

from p3d_cli.errors import UsageError


@dataclass(frozen=True)
class Step:
    """One repair step.

    Attributes
    ----------
    name : str
        Its name in ``steps=`` (``--steps``) and in the report.
    summary : str
        What it does, in one line (help text and docs/repair.md).
    default : bool
        Whether it runs when no steps are named (``weld`` runs only with a tolerance).
    """

    name: str
    summary: str
    default: bool = True


#: Every step, in the order they run.
STEPS: dict[str, Step] = {s.name: s for s in (
    Step("weld", "merge vertices closer than the weld tolerance (only with a tolerance)", default=False),
    Step("degenerate", "remove faces of exactly zero area (collinear or repeated corners)"),
    Step("duplicate", "remove faces with the same three vertices as an earlier face"),
    Step("orient", "flip faces so that each edge between two faces is used once each way "
                   "(the fewer faces of each shell)"),
    Step("holes", "fill holes bounded by simple, flat loops with triangles of their own corners"),
    Step("outward", "flip whole closed shells to face outward, shells inside shells as cavities"),
)}


def resolve_steps(steps: Iterable[str] | str | None, weld: float | None) -> tuple[str, ...]:
    """The steps to run, in their order.

    Parameters
    ----------
    steps : iterable of str, comma-separated str, or None
        None: every default step (and ``weld`` when ``weld`` is given). Names run those
        steps only; ``-name`` (or ``no-name``) leaves one out of the defaults; ``all`` is every
        default step; ``none`` nothing (a report only).
    weld : float or None
        The weld tolerance; the ``weld`` step needs one, and a tolerance without the step is
        refused.

    Raises
    ------
    UsageError
    """
    if isinstance(steps, str):
        steps = [steps]
    words = [w.strip().lower() for part in (steps or ()) for w in part.split(",") if w.strip()]
    defaults = [name for name, s in STEPS.items() if s.default or (name == "weld" and weld is not None)]
    positive = [w for w in words if not _negated(w)]
    chosen: set[str] = set(defaults) if steps is None or not positive else set()
    for word in words:
        if word == "all":
            chosen.update(defaults)
        elif word == "none":
            chosen.clear()
        elif _negated(word):
            chosen.discard(_known(_negated(word) or ""))
        else:
            chosen.add(_known(word))
    if "weld" in chosen and weld is None:
        raise UsageError("steps", "the weld step needs a tolerance", "give weld=TOL (the largest distance to merge)")
    if weld is not None and "weld" not in chosen:
        raise UsageError("weld", "a weld tolerance was given but the weld step is left out",
                         "drop the tolerance, or add weld to steps")
    return tuple(name for name in STEPS if name in chosen)


def _negated(word: str) -> str | None:
    """``name`` for ``-name`` or ``no-name``, else None."""
    if word.startswith("-"):
        return word[1:]
    if word.startswith("no-"):
        return word[3:]
    return None


def _known(name: str) -> str:
    if name not in STEPS:
        raise UsageError("steps", f"no repair step named {name!r}",
                         "steps are: " + ", ".join(STEPS) + " (or all, none; -NAME leaves one out)")
    return name
