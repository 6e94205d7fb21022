"""Constraints between rigid bodies (the Physics3D note's section 2; docs/method.md, "Constraints") and ``p3d solve``.

- ``scene``: the YAML scene format, validated into frozen values (``load_scene``).
- ``bodies``: mass properties, resolved only when needed.
- ``ball``, ``hinge``, ``bar``: one module per constraint type (``registry`` names them).
- ``islands``, ``solver``: the system of eq. 20, island by island, dense or sparse.
- ``world``, ``simulation``: one velocity solve, or stepping in time (``solve_scene``).
"""

from p3d_cli.constraints.outcome import BodyState, ConstraintOutcome, SolveResult
from p3d_cli.constraints.scene import Scene, load_scene, parse_scene
from p3d_cli.constraints.simulation import TRAJECTORY_HEADER, solve_scene, trajectory_row

__all__ = ["BodyState", "ConstraintOutcome", "Scene", "SolveResult", "TRAJECTORY_HEADER", "load_scene",
           "parse_scene", "solve_scene", "trajectory_row"]
