"""``p3d repair``: fix what ``p3d check`` finds, change nothing else, and say every change.

>>> import p3d_cli as p3d                                       # doctest: +SKIP
>>> mesh, report = p3d.repair("part.stl")
>>> report.fixed, report.mass.relative_volume_change
>>> p3d.repair_file("part.stl", "fixed.stl", max_volume_change=1e-6).ok

The steps (``p3d_cli.repairs.steps``) run in one order on ``p3d check``'s own topology
(``p3d_cli.repairs.pipeline``); the faces they do not touch keep their coordinates bit for bit,
and the output is checked again with ``check``'s code before it is called fixed.
"""

from __future__ import annotations

from p3d_cli.repairs.repaired import RepairedMesh, repair, repair_file
from p3d_cli.repairs.report import MassChange, RepairReport, StepReport
from p3d_cli.repairs.steps import STEPS

__all__ = ["STEPS", "MassChange", "RepairReport", "RepairedMesh", "StepReport", "repair", "repair_file"]
