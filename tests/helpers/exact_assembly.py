"""An exact oracle for placed and assembled parts: rational arithmetic on the float inputs.

The reference every stated ``uncertainty`` is held to (docs/accuracy.md, "Placed parts and
assemblies"): the mesh's coordinates, the placements' scale factors, rotation matrices and
translations exactly as the floats p3d holds them; each level's placement applied in turn by
the formulas of docs/method.md, "Placement order" (``V' = |det S| V``, ``c' = R S c + t``,
``C' = |det S| R S C S Rᵀ``: a rotation keeps the volume by definition); unit factors exact
(1 mm is 1/1000 m, 1 in is 127/5000 m); then the parts summed with the parallel-axis terms.
No step rounds: only the comparison does.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from helpers.exact import exact_moments

#: Length units in metres, exactly (the inch and the foot by the 1959 agreement).
EXACT_LENGTHS = {"mm": Fraction(1, 1000), "cm": Fraction(1, 100), "m": Fraction(1),
                 "in": Fraction(127, 5000), "ft": Fraction(381, 1250)}

Vec = list  # three Fractions
Mat = list  # three rows of three Fractions


def fr(x) -> Fraction:
    return Fraction(float(x))


def vec(a) -> Vec:
    return [fr(x) for x in np.asarray(a, dtype=np.float64).reshape(3)]


def mat(a) -> Mat:
    return [[fr(x) for x in row] for row in np.asarray(a, dtype=np.float64).reshape(3, 3)]


def matmul(a: Mat, b: Mat) -> Mat:
    return [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]


def matvec(a: Mat, v: Vec) -> Vec:
    return [sum(a[i][k] * v[k] for k in range(3)) for i in range(3)]


def transpose(a: Mat) -> Mat:
    return [[a[j][i] for j in range(3)] for i in range(3)]


@dataclass(frozen=True)
class ExactPart:
    """A solid's exact volume ``V``, centre ``c`` and central second moments ``C`` (volume
    integrals), and its density."""

    volume: Fraction
    center: Vec
    central: Mat
    density: Fraction = Fraction(1)

    @classmethod
    def of_triangles(cls, triangles, density=1.0) -> "ExactPart":
        m = exact_moments(np.asarray(triangles, dtype=np.float64))
        central = [list(row) for row in m.central]
        volume, c = m.volume, list(m.center)
        if volume < 0:  # measured as the enclosed solid, as p3d does
            volume, central = -volume, [[-x for x in row] for row in central]
        return cls(volume, c, central, fr(density) if not isinstance(density, Fraction) else density)

    def placed(self, scale=None, rotation=None, translation=None) -> "ExactPart":
        """This part after ``scale`` (floats; negative mirrors), ``rotation`` (a float matrix)
        and ``translation``, each exactly as given (``Fraction`` values are taken as they are)."""
        s = [Fraction(1)] * 3 if scale is None else [x if isinstance(x, Fraction) else fr(x) for x in scale]
        r = [[Fraction(int(i == j)) for j in range(3)] for i in range(3)] if rotation is None else mat(rotation)
        t = [Fraction(0)] * 3 if translation is None else [x if isinstance(x, Fraction) else fr(x)
                                                         for x in translation]
        det = abs(s[0] * s[1] * s[2])
        a = [[r[i][j] * s[j] for j in range(3)] for i in range(3)]       # R S
        center = [x + y for x, y in zip(matvec(a, self.center), t)]
        central = matmul(matmul(a, self.central), transpose(a))
        return ExactPart(det * self.volume, center, [[det * x for x in row] for row in central], self.density)

    @property
    def mass(self) -> Fraction:
        return self.density * self.volume

    def second(self) -> Mat:
        """Central second moments of mass, ``ρ C``."""
        return [[self.density * x for x in row] for row in self.central]


@dataclass(frozen=True)
class ExactWhole:
    volume: Fraction
    mass: Fraction
    center: Vec
    second: Mat          # ∫ (x - c)(x - c)ᵀ dm

    def inertia(self) -> Mat:
        trace = self.second[0][0] + self.second[1][1] + self.second[2][2]
        return [[(trace if i == j else 0) - self.second[i][j] for j in range(3)] for i in range(3)]

    def floats(self) -> dict:
        """The exact values rounded once, for error measurement."""
        return {"volume": self.volume, "mass": self.mass, "center_of_mass": self.center,
                "inertia": self.inertia()}


def combine(parts: list[ExactPart]) -> ExactWhole:
    """Masses and volumes add; ``c = Σ mᵢcᵢ/M``; ``S = Σ (ρᵢCᵢ + mᵢ dᵢdᵢᵀ)``, ``dᵢ = cᵢ - c``."""
    volume = sum(p.volume for p in parts)
    mass = sum(p.mass for p in parts)
    center = [sum(p.mass * p.center[i] for p in parts) / mass for i in range(3)]
    second = [[Fraction(0)] * 3 for _ in range(3)]
    for p in parts:
        d = [p.center[i] - center[i] for i in range(3)]
        own = p.second()
        for i in range(3):
            for j in range(3):
                second[i][j] += own[i][j] + p.mass * d[i] * d[j]
    return ExactWhole(volume, mass, center, second)


def whole_of(part: ExactPart) -> ExactWhole:
    return ExactWhole(part.volume, part.mass, part.center, part.second())


def error_ratios(result, exact: ExactWhole) -> dict[str, float]:
    """``|value - exact| / stated bound`` for each reported quantity (worst entry per key);
    ``inf`` where the error is non-zero and the bound zero."""
    p, u = result.properties, result.uncertainty
    values = {"volume": p.volume, "mass": p.mass, "center_of_mass": p.center_of_mass, "inertia": p.inertia}
    out = {}
    for key, want in exact.floats().items():
        got = np.asarray(values[key], dtype=np.float64)
        bound = np.asarray(u[key], dtype=np.float64)
        flat_want = np.ravel(np.array(want, dtype=object))
        errors = np.array([float(abs(Fraction(float(g)) - w)) for g, w in zip(got.ravel(), flat_want)])
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(errors == 0, 0.0, errors / bound.ravel())
        out[key] = float(ratio.max())
    return out
