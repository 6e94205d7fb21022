"""What ``p3d_cli.mesh.topology`` reports: counts, sample locations and shells."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from p3d_cli.mesh.solidity_report import Nesting, SelfIntersections

#: Sample locations kept per kind of problem.
SAMPLES = 5


@dataclass(frozen=True)
class EdgeSample:
    """One problem edge: its two end points and the faces that use it.

    Attributes
    ----------
    faces : tuple of int
        Indices of the faces using the edge (0-based, in file order).
    points : ((3,), (3,)) tuple of float tuples
        The edge's two end points.
    """

    faces: tuple[int, ...]
    points: tuple[tuple[float, float, float], tuple[float, float, float]]


@dataclass(frozen=True)
class VertexSample:
    """One non-manifold vertex: where it is and some faces around it."""

    faces: tuple[int, ...]
    point: tuple[float, float, float]


@dataclass(frozen=True)
class Shell:
    """One connected shell.

    Attributes
    ----------
    faces : int
        Number of faces in the shell.
    first_face : int
        Its lowest face index (to find it in the file).
    volume : float
        Signed volume enclosed by the shell's faces (negative when wound inward; an inner
        cavity of a solid is a negative shell).
    """

    faces: int
    first_face: int
    volume: float


@dataclass(frozen=True)
class TopologyReport:
    """What ``topology`` found in a triangle soup.

    Counts are exact; each ``*_samples`` tuple holds at most ``SAMPLES`` locations. Face
    indices are 0-based positions in the input (file order, polygons split into fans).
    ``shells`` counts every shell; ``shell_list`` holds at most ``LISTED_SHELLS`` of them,
    largest first (ties by first face).
    """

    faces: int
    vertices: int
    edges: int
    boundary_edges: int
    nonmanifold_edges: int
    misoriented_edges: int
    nonmanifold_vertices: int
    zero_area_faces: int
    faces_with_repeated_vertex: int
    degenerate_faces: int
    duplicate_faces: int
    shells: int
    shell_list: tuple[Shell, ...]
    volume: float
    """The faces' signed volume (negative when wound inward)."""
    boundary_edge_samples: tuple[EdgeSample, ...] = ()
    nonmanifold_edge_samples: tuple[EdgeSample, ...] = ()
    misoriented_edge_samples: tuple[EdgeSample, ...] = ()
    nonmanifold_vertex_samples: tuple[VertexSample, ...] = ()
    degenerate_face_samples: tuple[int, ...] = ()
    duplicate_face_samples: tuple[tuple[int, int], ...] = ()
    #: Face pairs whose interiors cross or overlap (``p3d_cli.mesh.intersections``); None when
    #: the test was not asked for.
    self_intersections: SelfIntersections | None = None
    #: How the closed shells nest (``p3d_cli.mesh.nesting``); None when not asked for.
    nesting: Nesting | None = None

    @property
    def closed(self) -> bool:
        return (self.faces > 0 and self.edges > 0 and self.boundary_edges == 0
                and self.nonmanifold_edges == 0 and self.misoriented_edges == 0)

    @property
    def oriented(self) -> bool:
        return self.misoriented_edges == 0

    @property
    def manifold(self) -> bool:
        return self.nonmanifold_edges == 0 and self.nonmanifold_vertices == 0

    @property
    def solid_volume(self) -> float:
        """The volume ``props`` reports for the same faces: the solid they enclose, so positive
        for an inward-wound mesh too (``volume`` keeps the sign; docs/method.md, "Inward-wound
        meshes"). Every command reports this one quantity as the volume."""
        return abs(self.volume)

    def in_length_unit(self, factor: float) -> "TopologyReport":
        """This report with its lengths multiplied by ``factor`` (volumes by ``factor³``): the
        file's declared unit made metres, as every command reports such a file. Counts and
        verdicts do not change: the topology was found on the coordinates as stored."""
        if factor == 1.0:
            return self

        def edges(samples):
            return tuple(EdgeSample(e.faces, tuple(_scaled(p, factor) for p in e.points)) for e in samples)

        cube = factor ** 3
        return dataclasses.replace(
            self, volume=self.volume * cube,
            shell_list=tuple(Shell(s.faces, s.first_face, s.volume * cube) for s in self.shell_list),
            boundary_edge_samples=edges(self.boundary_edge_samples),
            nonmanifold_edge_samples=edges(self.nonmanifold_edge_samples),
            misoriented_edge_samples=edges(self.misoriented_edge_samples),
            nonmanifold_vertex_samples=tuple(VertexSample(v.faces, _scaled(v.point, factor))
                                             for v in self.nonmanifold_vertex_samples),
            self_intersections=None if self.self_intersections is None
            else self.self_intersections.in_length_unit(factor),
            nesting=None if self.nesting is None else self.nesting.in_length_unit(factor))


def _scaled(point, factor: float):
    x, y, z = point
    return (x * factor, y * factor, z * factor)
