"""The one registry of constraint types: type name -> the module implementing it.

Each module is its type's record: ``KEYS`` (its scene entry's keys besides ``type``, ``a`` and
``b``), ``read(...)`` (its own values of an entry), ``EQUATIONS`` (rows per constraint),
``jacobian(geo)``, ``position_error(spec, geo)`` and ``impulse(geo, lam)``. The scene reader,
the row layout and the small-scene joints take these from here.
"""

from __future__ import annotations

from p3d_cli.constraints import ball, bar, hinge

CONSTRAINT_TYPES = {"ball": ball, "hinge": hinge, "bar": bar}
