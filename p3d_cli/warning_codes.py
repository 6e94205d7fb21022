"""Stable codes for p3d's warnings, so that a user can name one (``--ignore-warning CODE``).

A warning is a sentence for people; its code is a short name for programs and settings
(``open``, ``coarse-float32``). Every warning p3d makes is a ``CodedWarning``: a ``str`` (so
every use of a warning as text keeps working) that also carries its ``code``, given where the
warning is made, and, where the warning has a threshold, the measured ``value``. No code is
ever recovered from a warning's text; the results refuse a warning without one (``coded``).
"""

from __future__ import annotations

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

#: Warnings with a threshold: code -> the library's default (a threshold may only be raised:
#: below the default the library does not warn at all).
THRESHOLDS: dict[str, float] = {"coarse-float32": 1e-6}


class CodedWarning(str):
    """A warning's text that also knows its code (and its measured value, if it has a threshold).

    Every warning p3d makes is one, made where the condition is found: the code is never
    guessed from the text afterwards.

    Parameters
    ----------
    text : str
    code : str
        One of ``CODES``.
    value : float, optional
        The quantity compared with the warning's threshold (``THRESHOLDS``).

    Raises
    ------
    ValueError
        ``code`` is not one of ``CODES``.
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

    def named(self, name: str) -> "CodedWarning":
        """The same warning said of a part: ``"NAME: text"``, with its code and value kept."""
        return CodedWarning(f"{name}: {self}", self.code, self.value)


def coded(warnings, where: str = "warnings") -> tuple[CodedWarning, ...]:
    """``warnings`` as a tuple, each checked to carry its code.

    Raises
    ------
    TypeError
        A warning is a plain string (made without a code): a defect of the code that made it.
    """
    out = tuple(warnings)
    for warning in out:
        if not isinstance(warning, CodedWarning):
            raise TypeError(f"{where}: a warning without a code (make it a CodedWarning where it is made): "
                            f"{str(warning)[:80]!r}")
    return out


def is_ignored(warning: CodedWarning, ignore=frozenset(), thresholds: dict[str, float] | None = None) -> bool:
    """Whether ``warning`` is silenced: its code is in ``ignore``, or its value is within the
    caller's threshold for its code (a warning without a value is never within a threshold)."""
    if warning.code in ignore:
        return True
    limit = (thresholds or {}).get(warning.code)
    return limit is not None and warning.value is not None and warning.value <= limit


def check_codes(codes, where: str = "ignore_warning") -> tuple[str, ...]:
    """``codes`` validated (UsageError naming ``where`` for an unknown one)."""
    from p3d_cli.errors import UsageError

    out = []
    for code in codes:
        if code not in CODES:
            raise UsageError(where, f"no warning code {code!r}", "codes are: " + ", ".join(CODES))
        out.append(code)
    return tuple(out)


__all__ = ["CODES", "THRESHOLDS", "CodedWarning", "check_codes", "coded", "is_ignored"]
