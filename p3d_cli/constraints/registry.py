"""The one registry of constraint types: type name -> the module implementing it.

Each module provides ``EQUATIONS`` (rows per constraint), ``jacobian(geo)``,
``position_error(spec, geo)`` and ``impulse(geo, lam)``.
"""

from __future__ import annotations

from p3d_cli.constraints import ball, bar, hinge

CONSTRAINT_TYPES = {"ball": ball, "hinge": hinge, "bar": bar}
