"""Units: the mesh's length unit, densities and masses with units, and the units of results.

A mesh file carries no unit. ``units="mm"`` says what its numbers (and the numbers given with
it: ``about``, ``translate``) are; a density or mass may carry its own unit (``"7.85 g/cm^3"``,
``"7850 kg/m^3"``, ``"2.5 lb"``). Given units, results are in SI (m, kg, kg·m²) unless
``output_units`` asks for others (``"mm,g"``). Without units nothing is converted: the numbers
are in the mesh's own units, and the density's (as before units existed).

Conversion is exact in the maths: a length factor ``f`` from the mesh unit to the output unit is
a uniform scale applied after the user's placement (eq. 9: ``V' = f³ V``, ``C' = f⁵ C``), and
the density is converted to output mass per output length cubed, so no result is converted
after the fact. Density and mass text is parsed by pint (https://pint.readthedocs.io: the
maintained reference units library, with the inch, pound and their kin defined exactly), which
is imported only when a unit is written: a bare number costs nothing.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from p3d_cli.errors import UsageError
from p3d_cli.warning_codes import CodedWarning

#: Length units of ``units`` and ``output_units``, in metres (the inch and foot are exact by
#: the 1959 international yard and pound agreement).
LENGTHS = {"mm": 1e-3, "cm": 1e-2, "m": 1.0, "in": 0.0254, "ft": 0.3048}

#: Mass units of ``output_units``, in kilograms (the pound exactly 0.45359237 kg).
MASSES = {"g": 1e-3, "kg": 1.0, "lb": 0.45359237}

#: Unit strings the command-line help shows; every one is checked to parse (tests/test_units.py).
EXAMPLES = ("7.85g/cm^3", "7850kg/m^3", "0.284lb/in^3", "2.5kg", "2.5lb", "500g")

#: The ``units`` record of a result measured without units.
MESH_UNITS = {"system": "mesh", "length": "mesh unit", "volume": "mesh unit^3",
              "density": "as given (default 1)", "mass": "density * volume",
              "inertia": "mass * mesh unit^2"}


@dataclass(frozen=True)
class UnitSystem:
    """How one measurement converts: the mesh's length unit and the output units.

    Attributes
    ----------
    mesh_length : str
        The unit of the mesh's coordinates (a key of ``LENGTHS``).
    length, mass : str
        Units of the results (keys of ``LENGTHS`` and ``MASSES``).
    density, mass_value : float or None
        The density (output mass per output length cubed) or the total mass (output mass unit),
        whichever was given.
    """

    mesh_length: str
    length: str
    mass: str
    density: float | None = None
    mass_value: float | None = None

    @property
    def factor(self) -> float:
        """Mesh length unit -> output length unit (the exact ratio rounded once)."""
        return length_factor(self.mesh_length, self.length)[0]

    @property
    def factor_error(self) -> float:
        """How far ``factor`` is from the exact ratio (at most half an ulp): it enters the
        stated bounds (docs/accuracy.md, "Placed parts and assemblies")."""
        return length_factor(self.mesh_length, self.length)[1]

    def describe(self) -> dict:
        """The ``units`` record of a result: the unit of every quantity."""
        L, M = self.length, self.mass
        return {"system": "SI" if (L, M) == ("m", "kg") else "converted", "length": L,
                "volume": f"{L}^3", "density": f"{M}/{L}^3", "mass": M, "inertia": f"{M}*{L}^2",
                "mesh_length": self.mesh_length}


def exact_length(unit: str) -> Fraction:
    """A length unit of ``LENGTHS`` in metres, exactly (``1 in`` is ``127/5000 m``): the
    decimal the table is written in, not its float."""
    return Fraction(repr(LENGTHS[unit]))


@functools.lru_cache(maxsize=None)
def length_factor(unit: str, to: str) -> tuple[float, float]:
    """The factor from length unit ``unit`` to ``to``, rounded once from the exact ratio, and
    a bound on its rounding error (0 when the ratio is a float, as for ``m`` to ``in``'s
    reciprocal never is).

    Returns
    -------
    factor, error : float
    """
    exact = exact_length(unit) / exact_length(to)
    return float(exact), rounding_error(exact)


def rounding_error(exact: Fraction) -> float:
    """``|float(exact) - exact|``, rounded up: the error of rounding ``exact`` once."""
    try:
        error = abs(Fraction(float(exact)) - exact)
    except OverflowError:
        return math.inf
    if error == 0:
        return 0.0
    bound = float(error)
    return bound if Fraction(bound) >= error else math.nextafter(bound, math.inf)


def exact_products(values, factor: Fraction):
    """``values · factor`` each rounded once from the exact product, and the roundings.

    Parameters
    ----------
    values : (k,) float64
    factor : Fraction
        An exact unit ratio (``exact_length``).

    Returns
    -------
    products, roundings : (k,) float64
        ``|products - exact|`` rounded up (``rounding_error``).
    """
    import numpy as np

    exact = [Fraction(x) * factor for x in values.tolist()]
    return np.array([float(v) for v in exact]), np.array([rounding_error(v) for v in exact])


def parse_output_units(text: str | None) -> tuple[str, str]:
    """``"mm,g"`` -> ``("mm", "g")``; ``"mm"`` -> ``("mm", "kg")``; None -> SI ``("m", "kg")``.

    Raises
    ------
    UsageError
        Not a length and a mass unit of the tables.
    """
    if text is None:
        return "m", "kg"
    hint = f"write LENGTH,MASS with LENGTH one of {', '.join(LENGTHS)} and MASS one of {', '.join(MASSES)}"
    parts = [p.strip() for p in str(text).split(",")]
    if len(parts) == 1:
        parts.append("kg")
    if len(parts) != 2 or parts[0] not in LENGTHS or parts[1] not in MASSES:
        raise UsageError("output_units", f"{text!r} is not a length and a mass unit", hint)
    return parts[0], parts[1]


def check_length(unit: str, name: str = "units") -> str:
    """``unit`` if it is a length unit of ``LENGTHS``, else ``UsageError`` naming ``name``."""
    if unit not in LENGTHS:
        raise UsageError(name, f"unknown length unit {unit!r}", "use one of " + ", ".join(LENGTHS))
    return unit


@functools.lru_cache(maxsize=1)
def _registry():
    import pint

    # Rational magnitudes: "7.85 g/cm^3" converts to exactly 7850 kg/m³ (with floats pint
    # gives 7849.999999999999), so a converted density or mass is its exact value rounded
    # once, an error of at most half an ulp that the stated bounds carry.
    try:
        # Pint's own cache of its parsed definition files (in the user's cache directory)
        # makes the registry three times quicker to build; without it pint still works.
        return pint.UnitRegistry(cache_folder=":auto:", non_int_type=Fraction)
    except Exception:  # noqa: BLE001 - an unwritable cache must not stop a measurement
        return pint.UnitRegistry(non_int_type=Fraction)


def has_unit(value: Any) -> bool:
    """True for text that is not a bare number (so carries a unit)."""
    if not isinstance(value, str):
        return False
    try:
        float(value)
    except ValueError:
        return True
    return False


def quantity_si(text: str, kind: str, name: str) -> float:
    """The SI value of a density (kg/m³) or mass (kg) written with a unit.

    Parameters
    ----------
    text : str
        ``"7.85 g/cm^3"``, ``"2.5lb"``: a number and a unit, as pint reads them (``^`` or
        ``**`` for powers; ``g/cc`` too).
    kind : {"density", "mass"}
    name : str
        The parameter's name, for errors.

    Raises
    ------
    UsageError
        Not a quantity, the wrong dimension, or not positive and finite.
    """
    value = exact_quantity(text, kind, name)
    try:
        return float(value)
    except OverflowError:
        raise UsageError(name, f"{text!r} is not positive and finite", _hint(kind)) from None


def _hint(kind: str) -> str:
    return "write a number and a unit, e.g. " + ("7.85g/cm^3 or 7850kg/m^3" if kind == "density"
                                                 else "2.5kg or 5.5lb")


def exact_quantity(text: str, kind: str, name: str) -> Fraction:
    """``quantity_si``'s value exactly, as a ``Fraction`` (the decimal written, converted by
    exact unit definitions); ``UsageError`` as there."""
    ureg = _registry()
    target = {"density": "kg/m^3", "mass": "kg"}[kind]
    try:
        q = ureg.Quantity(str(text).replace("³", "^3"))
        value = Fraction(q.to(target).magnitude)
    except Exception as exc:  # noqa: BLE001 - pint raises many kinds for bad text
        what = "is not a " + kind if "ensionality" in type(exc).__name__ else "is not a quantity"
        raise UsageError(name, f"{text!r} {what} ({type(exc).__name__})", _hint(kind)) from None
    if value <= 0:
        raise UsageError(name, f"{text!r} is not positive and finite", _hint(kind))
    return value


#: Relative error of a density or mass converted from text with a unit (``resolve``): one
#: rounding of the exact value, at most half an ulp (2⁻⁵³ relative, plus the subnormal case,
#: which ``density_for`` refuses).
DENSITY_ROUNDING = 2.0 ** -53


def _finite(value: Fraction, name: str, kind: str) -> float:
    try:
        out = float(value)
    except OverflowError:
        out = math.inf
    if not math.isfinite(out) or out <= 0:
        raise UsageError(name, f"the {kind} in the output units is beyond float64's range",
                         "check the value and its unit")
    return out


def _positive(value, name: str) -> float:
    import math

    x = float(value)
    if not math.isfinite(x) or x <= 0:
        raise UsageError(name, f"{value!r} is not positive and finite", "give a number greater than 0")
    return x


def resolve(units: str | None, output_units: str | None, density=None, mass=None,
            names: tuple[str, str] = ("density", "mass")) -> tuple[UnitSystem | None, float | None, float | None]:
    """The unit system of one measurement, and the density and mass to use with it.

    Parameters
    ----------
    units : str or None
        The mesh's length unit.
    output_units : str or None
        ``LENGTH,MASS`` of the results (default SI when units are given).
    density, mass : float or str, optional
        Bare numbers, or text with a unit.
    names : two str
        How the caller names density and mass in errors.

    Returns
    -------
    system : UnitSystem or None
        None when no unit was given anywhere: nothing is converted.
    density, mass : float or None
        In the output units (or as given, without units).

    Raises
    ------
    UsageError
        A unit written for the density or mass without the mesh's length unit, a bare number
        with units (which unit would it be in?), output units without units, bad text.
    """
    given = {names[0]: density, names[1]: mass}
    if units is None:
        for name, value in given.items():
            if has_unit(value):
                raise UsageError("units", f"{name}={value} has a unit, but the mesh's length unit is not given",
                                 "add units= with the unit of the mesh's coordinates (mm, cm, m, in, ft)")
        if output_units is not None:
            raise UsageError("output_units", "given without units=",
                             "say the mesh's length unit with units= first")
        return (None, None if density is None else _positive(density, names[0]),
                None if mass is None else _positive(mass, names[1]))
    length, mass_unit = parse_output_units(output_units)
    system = UnitSystem(check_length(units), length, mass_unit)
    for name, value in given.items():
        if value is not None and not has_unit(value):
            example = "7850kg/m^3 or 7.85g/cm^3" if name == names[0] else "2.5kg"
            raise UsageError(name, f"{value} has no unit, and units={units} is given",
                             f"write the unit, e.g. {example} (a bare number would be ambiguous)")
    out_density = out_mass = None
    # Converted exactly and rounded once: at most half an ulp off, which the stated bounds
    # carry (``DENSITY_ROUNDING``).
    unit_mass = Fraction(repr(MASSES[mass_unit]))
    if density is not None:
        exact = exact_quantity(density, "density", names[0]) * exact_length(length) ** 3 / unit_mass
        out_density = _finite(exact, names[0], "density")
    if mass is not None:
        out_mass = _finite(exact_quantity(mass, "mass", names[1]) / unit_mass, names[1], "mass")
    return (UnitSystem(system.mesh_length, length, mass_unit, out_density, out_mass), out_density, out_mass)


#: Densities and sizes of the classic slip: a mesh in millimetres with a density in kg/m³.
SLIP_SIZE = (10.0, 1000.0)
SLIP_DENSITY = (500.0, 25_000.0)


def slip_warning(size: float, density: float | None) -> CodedWarning | None:
    """The plausibility warning for a part of largest extent ``size`` (mesh units) measured with
    ``density`` and no units: in millimetres, a density in kg/m³ makes the mass 1e9 too large."""
    if density is None or not (SLIP_SIZE[0] <= size <= SLIP_SIZE[1]) or not (SLIP_DENSITY[0] <= density
                                                                             <= SLIP_DENSITY[1]):
        return None
    return CodedWarning(f"the part is {size:.3g} across and the density {density:.6g}, with no units given: if the "
                        "mesh is in millimetres and the density in kg/m³, the mass is 1e9 times too large; state "
                        f"both units (the mesh's as mm, the density as {density:g}kg/m^3) for SI results", "unit-slip")
