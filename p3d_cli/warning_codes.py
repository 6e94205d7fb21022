"""Stable codes for p3d's warnings, so that a user can name one (``--ignore-warning CODE``).

A warning is a sentence for people; its code is a short name for programs and settings
(``open``, ``coarse-float32``). Warnings p3d makes itself are ``CodedWarning`` strings
(a ``str`` that also carries ``code`` and, where the warning has a threshold, the measured
``value``), so every existing use of a warning as text keeps working. Warnings that arrive as
plain strings (from the mesh readers, from Monte Carlo) get their code from ``code_of``, which
matches them against ``PATTERNS``; a sentence no pattern knows gets ``FALLBACK``.
"""

from __future__ import annotations

import re

#: Every code, with what it means (the order of ``p3d props --help`` and docs/ci.md).
CODES: dict[str, str] = {
    "open": "the mesh is not closed: an open surface has no well-defined volume",
    "inward": "the signed volume is negative: faces point into the solid",
    "flat": "the mesh encloses no volume: centre of mass and inertia are undefined",
    "self-intersecting": "the surface intersects itself: faces cross or overlap (found exactly), or the inertia "
                         "is not a solid's (then it probably does)",
    "nested-shells": "a closed shell lies inside another wound alike (its volume is counted twice), or a "
                     "cavity lies in no body",
    "non-manifold": "an edge is used by more than two faces",
    "coarse-float32": "float32 coordinates far from the origin limit the accuracy "
                      "(threshold: spacing / part size, default 1e-6)",
    "inverted-tetrahedra": "tetrahedra listed inside out were counted with their positive volume",
    "skipped-lines": "the reader ignored lines or statements it does not read",
    "trailing-data": "the reader ignored bytes or values after the last element",
    "unit-slip": "the size suggests the file's units are not the ones assumed",
    "spec-shadows-file": "an input reads as a shape spec although a file of that name exists",
    "montecarlo-winding": "Monte Carlo ignores the winding (its volume is positive)",
    "montecarlo-open": "Monte Carlo on an open mesh counts escaping points as half inside",
    "montecarlo-empty": "no Monte Carlo sample fell inside the solid",
    "montecarlo-few-inside": "too few Monte Carlo samples fell inside for standard errors: bounds instead",
    "montecarlo-cap": "the sample count a Monte Carlo tolerance needs is over the cap",
    "montecarlo-flat-box": "the solid's bounding box is flat: nothing to sample",
    "implausible": "a result no solid has (non-positive mass, triangle inequality, centre outside)",
    "reader": "any other warning of a mesh reader (meshio's own messages among them)",
}

#: The code of a plain-string warning no pattern matches.
FALLBACK = "reader"

#: Warnings with a threshold: code -> the library's default (a threshold may only be raised:
#: below the default the library does not warn at all).
THRESHOLDS: dict[str, float] = {"coarse-float32": 1e-6}

#: Plain-string warnings -> codes: the first pattern (a regular expression, for ``re.search``;
#: compiled on first use, not at import: start-up time) that matches wins.
PATTERNS: tuple[tuple[str, str], ...] = (
    ("montecarlo-winding", r"Monte Carlo's inside test ignores the winding"),
    ("montecarlo-open", r"Monte Carlo on an open mesh"),
    ("montecarlo-empty", r"no Monte Carlo sample (of \d+ )?fell inside"),
    ("montecarlo-few-inside", r"Monte Carlo samples fell inside the solid \(fewer than"),
    ("montecarlo-cap", r"needs more than the cap of"),
    ("montecarlo-flat-box", r"bounding box is flat, so nothing was sampled"),
    ("implausible", r"are not both positive|break the triangle inequality|centre of mass lies outside the bounds"),
    ("open", r"\bmesh is not closed\b"),
    ("flat", r"encloses no volume"),
    ("inward", r"signed volume is negative"),
    ("self-intersecting", r"inertia is not a solid's|surface intersects itself"),
    ("nested-shells", r"is wound alike: its volume|wound as a cavity lies in no body"),
    ("coarse-float32", r"coordinates are float32"),
    ("inverted-tetrahedra", r"tetrahedra are listed inside out"),
    ("non-manifold", r"non-manifold"),
    ("spec-shadows-file", r"is read as a shape spec"),
    ("unit-slip", r"\bunits?\b"),
    ("skipped-lines", r"(lines?|statements?)\b.*\b(ignored|skipped)|(ignored|skipped)\b.*\b(lines?|statements?)\b"),
    ("trailing-data", r"(bytes|values|numbers)\b.*\bignored"),
)


class CodedWarning(str):
    """A warning's text that also knows its code (and its measured value, if it has a threshold).

    Parameters
    ----------
    text : str
    code : str
        One of ``CODES``.
    value : float, optional
        The quantity compared with the warning's threshold (``THRESHOLDS``).
    """

    code: str
    value: float | None

    def __new__(cls, text: str, code: str, value: float | None = None) -> "CodedWarning":
        if code not in CODES:
            raise ValueError(f"unknown warning code {code!r}")
        self = super().__new__(cls, text)
        self.code = code
        self.value = value
        return self

    def __reduce__(self):
        return (CodedWarning, (str(self), self.code, self.value))


def code_of(warning: str) -> str:
    """The code of a warning: its own, or the first of ``PATTERNS`` its text matches, or ``FALLBACK``."""
    code = getattr(warning, "code", None)
    if isinstance(code, str):
        return code
    for name, pattern in PATTERNS:
        if re.search(pattern, warning):
            return name
    return FALLBACK


def is_ignored(warning: str, ignore=frozenset(), thresholds: dict[str, float] | None = None) -> bool:
    """Whether ``warning`` is silenced: its code is in ``ignore``, or its value is within the
    caller's threshold for its code (a warning without a value is never within a threshold)."""
    code = code_of(warning)
    if code in ignore:
        return True
    limit = (thresholds or {}).get(code)
    value = getattr(warning, "value", None)
    return limit is not None and value is not None and value <= limit


def check_codes(codes, where: str = "ignore_warning") -> tuple[str, ...]:
    """``codes`` validated (UsageError naming ``where`` for an unknown one)."""
    from p3d_cli.errors import UsageError

    out = []
    for code in codes:
        if code not in CODES:
            raise UsageError(where, f"no warning code {code!r}", "codes are: " + ", ".join(CODES))
        out.append(code)
    return tuple(out)


__all__ = ["CODES", "FALLBACK", "PATTERNS", "THRESHOLDS", "CodedWarning", "check_codes", "code_of", "is_ignored"]
