"""What ``p3d_cli.mesh.topology`` reports: counts, sample locations and shells."""

from __future__ import annotations

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
