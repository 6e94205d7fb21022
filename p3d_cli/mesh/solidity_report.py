"""What ``p3d check`` reports about a mesh bounding a solid: self-intersections (face pairs, their
kinds and where they meet) and the nesting of its closed shells."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

#: Sample locations kept (as for the topology's problems).
SAMPLES = 5


@dataclass(frozen=True)
class Crossing:
    """One pair of faces that cross or overlap.

    Attributes
    ----------
    faces : (int, int)
        Face indices (0-based, file order), the smaller first.
    kind : str
        ``crossing`` (the surfaces pass through each other), ``overlap`` (coplanar faces
        facing the same way share a region: it is counted twice) or ``fold`` (coplanar faces
        sharing an edge lie on each other: the surface turns back on itself).
    point : (float, float, float)
        A point where they meet (inside both faces; for coplanar faces, inside their overlap).
    """

    faces: tuple[int, int]
    kind: str
    point: tuple[float, float, float]


@dataclass(frozen=True)
class SelfIntersections:
    """The face pairs whose interiors cross or overlap (``p3d_cli.mesh.intersections``).

    Attributes
    ----------
    count : int
        Number of such face pairs.
    by_kind : dict
        ``{"crossing": n, "overlap": n, "fold": n}``.
    samples : tuple of Crossing
        The first ``SAMPLES`` pairs in face order, with a point on each.
    pairs : (count, 2) int64
        Every pair, sorted (the smaller face first).
    kinds : (count,) str
        The kind of each pair.
    faces_tested : int
        Faces that took part (degenerate faces are the ``no-degenerate`` check's, not tested).
    """

    count: int
    by_kind: dict
    samples: tuple[Crossing, ...] = ()
    pairs: np.ndarray = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64), repr=False)
    kinds: tuple[str, ...] = field(default=(), repr=False)
    faces_tested: int = 0

    def in_length_unit(self, factor: float) -> "SelfIntersections":
        """These pairs with their points' coordinates multiplied by ``factor``."""
        samples = tuple(replace(c, point=(c.point[0] * factor, c.point[1] * factor, c.point[2] * factor))
                        for c in self.samples)
        return replace(self, samples=samples)

    def to_dict(self, all_pairs: bool = False) -> dict:
        """The JSON record (``all_pairs``: every pair, not only the samples)."""
        out = {"count": self.count, "by_kind": dict(self.by_kind), "faces_tested": self.faces_tested,
               "samples": [{"faces": list(c.faces), "kind": c.kind, "point": list(c.point)}
                           for c in self.samples]}
        if all_pairs:
            out["pairs"] = [[int(a), int(b), k] for (a, b), k in zip(self.pairs.tolist(), self.kinds)]
        return out


@dataclass(frozen=True)
class ShellPlace:
    """One closed shell and where it lies.

    Attributes
    ----------
    shell : int
        Its number (shells are numbered by their first face).
    faces, first_face : int
    volume : float
        Signed volume enclosed by its faces.
    inside : int or None
        The smallest shell it lies in (None: in none).
    winding : int
        The winding number just inside it (its own sign plus that of every shell around it).
    """

    shell: int
    faces: int
    first_face: int
    volume: float
    inside: int | None
    winding: int


@dataclass(frozen=True)
class Nesting:
    """The closed shells of a mesh, how they nest and cross, and the volume counted wrongly.

    Attributes
    ----------
    shells : tuple of ShellPlace
        The ``nesting.LISTED`` largest closed shells.
    closed_shells : int
        Closed shells in all (shells with a boundary, non-manifold or misoriented edge are
        left out: they bound no region of their own).
    relations : tuple of (int, int, str)
        ``(a, b, "inside")``: shell a lies in shell b; ``(a, b, "crossing")``: their faces
        intersect; ``(a, b, "coincident")``: every tested vertex of a lies on b's surface.
    counted_twice : float
        Volume the integrals count more than once (exact for nested shells; crossing shells
        add ``crossing_bound`` at most).
    counted_negative : float
        Volume counted with the wrong sign (a cavity that lies in no body).
    crossing_bound : float
        For crossing shells wound alike: the smaller one's volume, a bound on their common
        region (counted twice); 0 when no such shells cross.
    """

    shells: tuple[ShellPlace, ...]
    closed_shells: int
    relations: tuple[tuple[int, int, str], ...]
    counted_twice: float
    counted_negative: float
    crossing_bound: float
    #: Every closed shell's enclosing shell (None: in none) and signed volume, by shell number.
    parent: dict = field(default_factory=dict, repr=False)
    volumes: dict = field(default_factory=dict, repr=False)

    @property
    def ok(self) -> bool:
        """Whether the shells nest as a solid's (nothing counted twice or negative, no crossing)."""
        return (self.counted_twice == 0 and self.counted_negative == 0
                and not any(kind != "inside" for _, _, kind in self.relations))

    def in_length_unit(self, factor: float) -> "Nesting":
        """This nesting with its volumes multiplied by ``factor³``."""
        cube = factor ** 3
        return replace(self, shells=tuple(replace(s, volume=s.volume * cube) for s in self.shells),
                       counted_twice=self.counted_twice * cube, counted_negative=self.counted_negative * cube,
                       crossing_bound=self.crossing_bound * cube,
                       volumes={k: v * cube for k, v in self.volumes.items()})

    def to_dict(self) -> dict:
        return {"ok": self.ok, "closed_shells": self.closed_shells,
                "shells": [{"shell": s.shell, "faces": s.faces, "first_face": s.first_face, "volume": s.volume,
                            "inside": s.inside, "winding": s.winding} for s in self.shells],
                "relations": [{"shell": a, "other": b, "relation": kind} for a, b, kind in self.relations],
                "counted_twice": self.counted_twice, "counted_negative": self.counted_negative,
                "crossing_bound": self.crossing_bound}
