"""Does a mesh bound a solid? Its self-intersections and its shells' nesting, added to the
topology report of ``p3d check`` (the passes that need the vertex ids the topology found)."""

from __future__ import annotations

import dataclasses

from p3d_cli.mesh.intersections import self_intersections
from p3d_cli.mesh.layout import Layout, vertex_points
from p3d_cli.mesh.nesting import shell_nesting
from p3d_cli.mesh.report import TopologyReport


def with_solidity(report: TopologyReport, blocks, layout: Layout, patches=None, nearby=None) -> TopologyReport:
    """``report`` with its ``self_intersections`` and its shells' ``nesting`` (one more pass
    over ``blocks()`` for the vertices' coordinates). ``patches``: faces known to meet each
    other only in shared edges and corners, by label; ``nearby``: with them, every pair with
    a face in a patch that may touch (``self_intersections``)."""
    points, rank = vertex_points(blocks, layout)
    faces = layout.faces
    crowded = rank[layout.crowded_edges] if len(layout.crowded_edges) else layout.crowded_edges
    fans = report.closed and report.nonmanifold_vertices == 0
    found = self_intersections(points, faces, layout.zero_area, crowded, fans=fans, patches=patches,
                               nearby=nearby)
    nesting = shell_nesting(points, faces, layout, found.pairs, report.volume)
    return dataclasses.replace(report, self_intersections=found, nesting=nesting)
