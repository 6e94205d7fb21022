"""Maths on arrays and values, below the mesh layer: nothing here reads a file or knows a command.

Rotations and quaternions (``rotation``), volume moments and how a placement moves them
(``moments``), mass properties from moments (``inertia``), exact axis-aligned bounds
(``bounding``), placements and their composition with rounding bounds (``placement``; what users
write is read into one by ``p3d_cli.io.placements``), error-free float arithmetic (``expansions``), and the
exact orientation predicates (``predicates``, on ``rational``'s exact vectors) that the
self-intersection and nesting tests are built on.
"""
