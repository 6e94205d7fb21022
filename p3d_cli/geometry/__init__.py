"""Maths on arrays and values, below the mesh layer: exact geometric predicates.

``p3d_cli.geometry.predicates`` decides orientation signs exactly (a float filter with a proven
error bound, then exact integer arithmetic on the dyadic rationals the floats are); the
self-intersection test (``p3d_cli.mesh.intersections``) and the shells' nesting test are built
on them.
"""
