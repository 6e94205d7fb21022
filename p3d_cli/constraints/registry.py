"""The one registry of constraint types: type name -> the module implementing it.

Each module is its type's one record: ``KEYS`` (its scene entry's keys besides ``type``, ``a``
and ``b``), ``read(...)`` (its own values of an entry, kept as ``ConstraintSpec.values``),
``EQUATIONS`` (rows per constraint), ``TURNED`` (the body-frame vectors among those values that
its world geometry turns, with their side), ``jacobian(geo)``, ``position_error(spec, geo)`` and
``impulse(geo, lam)`` (one constraint: the statement of its equations, and the report),
``Rows`` (its array form over a scene's constraints of the type, ``rows.RowSet``) and
``SmallJoint`` (its scalar form for small scenes, a ``scalar.Joint``). The scene reader, the row
layout, the small-scene step and the report take these from here and name no type.
"""

from __future__ import annotations

from p3d_cli.constraints import ball, bar, hinge

CONSTRAINT_TYPES = {"ball": ball, "hinge": hinge, "bar": bar}
