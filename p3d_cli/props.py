"""``props``: the mass properties of one input, as the library computes them.

This is the function behind ``p3d props``; the CLI only parses options and formats the
``PropsResult`` this returns.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from p3d_cli.io import load_mesh
from p3d_cli.massprops import mass_properties
from p3d_cli.mesh.analysis import analyze
from p3d_cli.results import MeshFacts, Moments, PropsResult

#: A float32 file whose coordinate spacing exceeds this fraction of the part's size is
#: coarse: the file itself, not the arithmetic, limits the accuracy (FACTS.md, "Float32 input").
COARSE_FLOAT32 = 1e-6


def mesh_props(source: str, *, fmt: str | None = None, density: float | None = None,
               mass: float | None = None, about=None, stdin=None, placement=None) -> PropsResult:
    """Mass properties of a mesh file (or ``-`` for standard input).

    Parameters
    ----------
    source : str
        Path, or ``-``.
    fmt : str, optional
        Format override.
    density, mass : float, optional
        Exclusive; default density 1.
    about : (3,) array_like, optional
        Extra reference point for the inertia.
    placement : p3d_cli.placed.Placement, optional
        Scale, rotate and move the solid: its moments are placed by eq. 9 and ``R C Rᵀ``
        from the unplaced integrals, and ``facts.bounds`` become the placed solid's.

    Returns
    -------
    PropsResult

    Raises
    ------
    InputError, UsageError
    """
    mesh = load_mesh(source, fmt, stdin=stdin)
    where = "<stdin>" if source == "-" else source
    if placement is not None:
        from p3d_cli.placed import watch_bounds
        mesh, placed_bounds = watch_bounds(mesh, placement)
    found = analyze(mesh, where)
    facts = MeshFacts(source, mesh.format, found.face_count, found.closed, found.bounds,
                      mesh.coordinate_dtype)
    warnings = list(mesh.warnings) + mesh_warnings(found.moments, facts)
    if found.inverted_tetrahedra:
        warnings.append(f"{found.inverted_tetrahedra} of {found.face_count} tetrahedra are listed inside "
                        "out (negative orientation); each was counted with its positive volume")
    moments = found.moments
    if placement is not None:
        moments = placement.moments(moments)
        facts = dataclasses.replace(facts, bounds=placed_bounds())
    props = mass_properties(moments, density=density, mass=mass, about=about)
    return PropsResult(facts, props, "exact", tuple(warnings), exact_uncertainty(moments, props))


def mesh_warnings(moments: Moments, facts: MeshFacts) -> list[str]:
    """Plain-words warnings for results that are not a clean solid's."""
    out = []
    if facts.closed is False:
        out.append("mesh is not closed (some edge is not shared by exactly two faces in opposite "
                   "directions, vertices matched by exact coordinates): an open surface has no "
                   "well-defined volume, and these numbers depend on the formula and the origin")
    if moments.is_empty:
        out.append("mesh encloses no volume (flat or degenerate): centre of mass and inertia are undefined")
    elif moments.volume < 0:
        what = "closed but wound inward" if facts.closed else "wound mostly inward"
        out.append(f"signed volume is negative: the mesh is {what} (faces point into the solid); "
                   "mass and inertia carry the same negative sign; reverse the face winding to fix")
    elif facts.closed:
        from p3d_cli.massprops import inertia_from_second_moments
        principal = np.linalg.eigvalsh(inertia_from_second_moments(moments.central))
        scale = max(abs(principal).max(), 1e-300)
        if principal[0] < -1e-9 * scale or principal[0] + principal[1] < principal[2] * (1 - 1e-9):
            out.append("inertia is not a solid's (a principal moment is negative or breaks the "
                       "triangle inequality): the mesh probably intersects itself")
    if facts.coordinate_dtype == "float32" and facts.bounds is not None:
        extent = float(np.abs(np.concatenate([facts.bounds.min, facts.bounds.max])).max())
        size = facts.bounds.diagonal
        spacing = extent * 2.0 ** -23
        if size > 0 and spacing > COARSE_FLOAT32 * size:
            out.append(f"coordinates are float32 and the part lies far from the origin: the file "
                       f"resolves only {spacing:.3g} ({spacing / size:.2g} of the part's size); the "
                       "file's precision, not p3d's arithmetic, limits these results; export in "
                       "float64 (ASCII or double PLY) or nearer the origin")
    return out


def exact_uncertainty(moments: Moments, props) -> dict | None:
    """A-priori rounding bounds of the exact method, mapped to the reported quantities."""
    errors = moments.errors
    if errors is None:
        return None
    out: dict = {"volume": errors.volume}
    if moments.is_empty:
        out.update(center_of_mass=None, inertia=None)
        return out
    density = abs(props.density)
    central = errors.central * density
    inertia = np.abs(np.trace(central)) * np.eye(3) + central
    # The last roundings happen after the sums: the centre is ``origin + offset`` (half an ulp
    # of the centre, which dominates far from the world origin: nothing finer is representable),
    # and mass, second moments and ``tr(S) E - S`` round a few more times.
    eps = np.finfo(np.float64).eps
    second = np.abs(props.second_moments)
    out["center_of_mass"] = errors.center + np.spacing(np.abs(props.center_of_mass))
    out["inertia"] = inertia + 4 * eps * (np.trace(second) * np.eye(3) + second)
    out["mass"] = errors.volume * density + float(np.spacing(abs(props.mass)))
    return out

