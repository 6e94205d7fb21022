"""Assemblies: several parts, each placed and of its own material, measured as one whole.

``parts`` reads them (the ``Part`` and ``Assembly`` values, assembly files and scene ``parts:``
lists), ``whole`` measures them (every part placed in one frame, then the sums), and ``check``
checks an assembly file part by part. Outside ``p3d_cli.measure`` these are reached through
``p3d_cli.measure``'s names.
"""
