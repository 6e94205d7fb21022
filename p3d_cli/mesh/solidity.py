"""Does a mesh bound a solid? Its self-intersections and its shells' nesting, added to the
topology report of ``p3d check`` (the passes that need the vertex ids the topology found)."""

from __future__ import annotations

import dataclasses

from p3d_cli.mesh.intersections import self_intersections
from p3d_cli.mesh.layout import Layout, vertex_points
from p3d_cli.mesh.nesting import shell_nesting
from p3d_cli.mesh.report import TopologyReport


def _renumbered(layout: Layout, faces, edges):
    """``edges`` (vertex ids of the topology) in ``faces``' numbering."""
    import numpy as np

    if len(edges) == 0:
        return edges
    old = layout.ids.reshape(-1, 3)
    mapping = {}
    for f in np.unique(np.isin(old, edges).any(axis=1).nonzero()[0]):
        for a, b in zip(old[f].tolist(), faces[f].tolist()):
            mapping[a] = b
    return np.array([[mapping[a], mapping[b]] for a, b in np.asarray(edges).tolist()], dtype=np.int64)


def with_solidity(report: TopologyReport, blocks, layout: Layout) -> TopologyReport:
    """``report`` with its ``self_intersections`` and its shells' ``nesting`` (one more pass
    over ``blocks()`` for the vertices' coordinates)."""
    points, faces = vertex_points(blocks, layout)
    crowded = _renumbered(layout, faces, layout.crowded_edges)
    found = self_intersections(points, faces, layout.zero_area, crowded)
    nesting = shell_nesting(points, faces, layout, found.pairs)
    return dataclasses.replace(report, self_intersections=found, nesting=nesting)
