"""The topology's general path, forced: the oracle its fast path is compared with.

``p3d_cli.mesh.topology`` tries the paired fast path first; with it refused, the same call
takes the general path, whose report and layout the fast path must give bit for bit.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import p3d_cli.mesh.topology as topo


@contextmanager
def fast_path_refused() -> Iterator[None]:
    """Within the block, the topology takes its general path for every mesh."""
    saved = topo.paired_topology
    topo.paired_topology = lambda *args, **kwargs: None
    try:
        yield
    finally:
        topo.paired_topology = saved


def real_surface_meshes(folder, limit: int = 200_000):
    """The real meshes of ``folder`` in the surface formats, of at most ``limit`` faces, loaded."""
    from p3d_cli.io import load_mesh

    for path in sorted(folder.iterdir()):
        if path.suffix.lower() not in (".stl", ".ply", ".obj", ".off"):
            continue
        mesh = load_mesh(str(path))
        if mesh.face_count <= limit:
            yield mesh
